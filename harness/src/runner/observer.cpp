#include "curvlab/harness/runner/observer.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace curvlab::harness::runner {

std::string_view to_string(ObserverModel m) {
  switch (m) {
    case ObserverModel::human: return "human";
    case ObserverModel::triangulation: return "triangulation";
    case ObserverModel::physical: return "physical";
    case ObserverModel::random: return "random";
    case ObserverModel::image: return "image";
  }
  return "?";
}

std::optional<ObserverModel> parse_observer_model(std::string_view text) {
  if (text == "human") return ObserverModel::human;
  if (text == "triangulation" || text == "perception") return ObserverModel::triangulation;
  if (text == "physical") return ObserverModel::physical;
  if (text == "random") return ObserverModel::random;
  if (text == "image") return ObserverModel::image;
  return std::nullopt;
}

Result<Done> check_observer(const ObserverParams& p) {
  const auto bad = [](const char* m) { return Error{Error::Kind::usage, m}; };
  if (!(std::abs(p.bias_m) <= 1.0)) return bad("bias_m must lie in [-1, 1] metres");
  if (!(std::abs(p.adaptation_m) <= 1.0)) return bad("adaptation_m must lie in [-1, 1] metres");
  if (!(p.slope_per_m > 0.0 && p.slope_per_m <= 1e6))
    return bad("slope_per_m must be a positive number (1 / noise SD in metres)");
  if (!(p.lapse >= 0.0 && p.lapse <= 1.0)) return bad("lapse must lie in [0, 1]");
  if (!(p.criterion_m >= 0.0 && p.criterion_m <= 1.0)) return bad("criterion_m must lie in [0, 1] metres");
  if (!(p.rt_base_ms >= 0.0 && p.rt_mean_extra_ms >= 0.0)) return bad("response-time parameters must not be negative");
  const auto& v = p.vision;
  if (!(v.vergence_weight >= 0.0 && v.vergence_weight <= 1.0)) return bad("vergence_weight must lie in [0, 1]");
  if (!(v.specific_distance_m >= 0.1 && v.specific_distance_m <= 50.0))
    return bad("specific_distance_m must lie in [0.1, 50] metres");
  if (!(v.threshold_arcsec > 0.0 && v.threshold_arcsec <= 3600.0))
    return bad("threshold_arcsec must lie in (0, 3600] arcseconds");
  if (!(v.pedestal_fraction >= 0.0 && v.pedestal_fraction <= 1.0)) return bad("pedestal_fraction must lie in [0, 1]");
  if (!(v.fusion_arcmin > 0.0 && v.fusion_arcmin <= 600.0)) return bad("fusion_arcmin must lie in (0, 600] arcminutes");
  if (!(v.divergence_limit_deg >= 0.0 && v.divergence_limit_deg <= 10.0))
    return bad("divergence_limit_deg must lie in [0, 10] degrees");
  if (!(v.convergence_limit_deg > 0.0 && v.convergence_limit_deg <= 60.0))
    return bad("convergence_limit_deg must lie in (0, 60] degrees");
  return Done{};
}

bool human_limits(ObserverModel m) { return m == ObserverModel::human || m == ObserverModel::image; }

std::span<const VisionSetting> vision_settings() {
  using V = geometry::HumanVision;
  static constexpr VisionSetting kSettings[] = {
      {"vergence_weight", &V::vergence_weight,
       "weight of the vergence distance against the specific distance, in dioptres (default 0.5)"},
      {"specific_distance_m", &V::specific_distance_m,
       "the distance perceived distance is pulled toward (default 1.0 m)"},
      {"threshold_arcsec", &V::threshold_arcsec, "stereo threshold: disparity noise SD at zero pedestal (default 30)"},
      {"pedestal_fraction", &V::pedestal_fraction, "rise of the threshold per unit of pedestal disparity (default 0.05)"},
      {"fusion_arcmin", &V::fusion_arcmin, "fusional limit: how far the eyes may miss a point and still fuse it (default 20 arcmin)"},
      {"divergence_limit_deg", &V::divergence_limit_deg, "how far the eyes diverge beyond parallel (default 1 degree)"},
      {"convergence_limit_deg", &V::convergence_limit_deg, "the largest vergence (default 35 degrees)"},
  };
  return kSettings;
}

std::string observer_json(const ObserverParams& p) {
  nlohmann::ordered_json j;
  j["model"] = std::string(to_string(p.model));
  j["bias_m"] = p.bias_m;
  j["adaptation_m"] = p.adaptation_m;
  j["slope_per_m"] = p.slope_per_m;
  j["lapse"] = p.lapse;
  j["criterion_m"] = p.criterion_m;
  j["rt_base_ms"] = p.rt_base_ms;
  j["rt_mean_extra_ms"] = p.rt_mean_extra_ms;
  j["seed"] = p.seed;
  if (human_limits(p.model)) {
    nlohmann::ordered_json v;
    for (const auto& f : vision_settings()) v[std::string(f.name)] = p.vision.*f.field;
    j["vision"] = v;
  }
  return j.dump();
}

Result<ObserverParams> observer_from_json(std::string_view json) {
  const auto d = nlohmann::json::parse(json, nullptr, false);
  if (d.is_discarded() || !d.is_object()) return Error{Error::Kind::corrupt, "the observer event is not a JSON object"};
  ObserverParams p;
  try {
    // Events written before the human model name the ideal geometer
    // "perception" and default to it.
    const std::string model = d.value("model", std::string("perception"));
    const auto parsed = parse_observer_model(model);
    if (!parsed)
      return Error{Error::Kind::corrupt, "its observer model is '" + model +
                                             "', not human, triangulation (perception), physical, random or image"};
    p.model = *parsed;
    p.bias_m = d.value("bias_m", p.bias_m);
    p.adaptation_m = d.value("adaptation_m", p.adaptation_m);
    p.slope_per_m = d.value("slope_per_m", p.slope_per_m);
    p.lapse = d.value("lapse", p.lapse);
    p.criterion_m = d.value("criterion_m", p.criterion_m);
    p.rt_base_ms = d.value("rt_base_ms", p.rt_base_ms);
    p.rt_mean_extra_ms = d.value("rt_mean_extra_ms", p.rt_mean_extra_ms);
    p.seed = d.value("seed", p.seed);
    if (const auto v = d.find("vision"); v != d.end() && v->is_object())
      for (const auto& f : vision_settings()) p.vision.*f.field = v->value(std::string(f.name), p.vision.*f.field);
  } catch (const nlohmann::json::exception& e) {
    return Error{Error::Kind::corrupt, std::string("the observer event has a field of the wrong type: ") + e.what()};
  }
  if (auto ok = check_observer(p); !ok) return Error{Error::Kind::corrupt, "the observer event: " + ok.error().message};
  return p;
}

double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }

SimulatedObserver::SimulatedObserver(const ObserverParams& params)
    : params_(params), rng_(protocol::mix_seed(params.seed ^ 0x6f62736572766572ULL)) {}

double SimulatedObserver::uniform() { return protocol::uniform01(rng_); }

double standard_normal(protocol::Engine& rng) {
  const double u1 = 1.0 - protocol::uniform01(rng);  // (0, 1]
  const double u2 = protocol::uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

namespace {

// The n−1 cuts, from the most positive down.
double cut(std::size_t k, std::size_t n, double criterion_m) {
  if (n <= 2) return 0.0;
  const double span = static_cast<double>(n - 2);
  return criterion_m * (span - 2.0 * static_cast<double>(k)) / span;
}

}  // namespace

std::vector<double> SimulatedObserver::choice_probabilities(double s, std::size_t n, double noise_sd_m) const {
  std::vector<double> p(n, 0.0);
  if (n == 0) return p;
  const double guess = 1.0 / static_cast<double>(n);
  if (params_.model == ObserverModel::random) {
    std::fill(p.begin(), p.end(), guess);
    return p;
  }
  const double mean = s + params_.bias_m;
  double above_prev = 0.0;  // P(L > previous cut); the first option is L > cut 0
  for (std::size_t k = 0; k < n; ++k) {
    const double above =
        k + 1 < n ? 1.0 - normal_cdf((cut(k, n, params_.criterion_m) - mean) / noise_sd_m)
                  : 1.0;
    p[k] = params_.lapse * guess + (1.0 - params_.lapse) * (above - above_prev);
    above_prev = above;
  }
  return p;
}

std::size_t SimulatedObserver::choose(double s, std::size_t n, double noise_sd_m) {
  if (n == 0) return 0;
  const double lapse_draw = uniform();
  const double option_draw = uniform();
  const double noise = standard_normal(rng_);
  if (params_.model == ObserverModel::random || lapse_draw < params_.lapse)
    return std::min(n - 1, static_cast<std::size_t>(option_draw * static_cast<double>(n)));
  const double latent = s + params_.bias_m + noise * noise_sd_m;
  for (std::size_t k = 0; k + 1 < n; ++k)
    if (latent > cut(k, n, params_.criterion_m)) return k;
  return n - 1;
}

double SimulatedObserver::adjust(const std::function<double(double)>& perceived, double lo, double hi,
                                 double noise_sd_m) {
  const double lapse_draw = uniform();
  const double where = uniform();
  const double noise = standard_normal(rng_) * noise_sd_m;
  if (params_.model == ObserverModel::random || lapse_draw < params_.lapse)
    return lo + where * (hi - lo);
  auto f = [&](double x) { return perceived(x) + params_.bias_m + noise; };
  double flo = f(lo);
  const double fhi = f(hi);
  if (flo == 0.0) return lo;
  if ((flo > 0.0) == (fhi > 0.0)) return std::abs(flo) < std::abs(fhi) ? lo : hi;
  for (int i = 0; i < 60 && hi - lo > 1e-7; ++i) {
    const double mid = 0.5 * (lo + hi);
    const double fm = f(mid);
    if ((fm > 0.0) == (flo > 0.0)) {
      lo = mid;
      flo = fm;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

std::int64_t SimulatedObserver::response_time_ns() {
  const double u = 1.0 - uniform();
  const double ms = params_.rt_base_ms - params_.rt_mean_extra_ms * std::log(u);
  return static_cast<std::int64_t>(ms * 1e6);
}

}  // namespace curvlab::harness::runner
