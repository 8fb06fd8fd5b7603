#include "curvlab/harness/lsl/session_streams.hpp"

#include "curvlab/harness/data/stream_log.hpp"

#ifdef CURVLAB_WITH_LSL
#include <lsl_cpp.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <limits>
#include <mutex>
#include <thread>
#endif

namespace curvlab::harness::lsl {

std::string unavailable_message() {
  return "this curvlab was built without Lab Streaming Layer support (liblsl was not found when it was "
         "configured): install liblsl (its GitHub releases, vcpkg `liblsl` or conda-forge `liblsl`), configure "
         "again with -DCMAKE_PREFIX_PATH=<liblsl prefix> and rebuild (docs/lsl.md, \"Building with LSL\")";
}

#ifndef CURVLAB_WITH_LSL

bool available() { return false; }
std::string library_version() { return {}; }
Result<std::unique_ptr<io::SessionStreams>> open(const StreamOptions&, const io::Clock&) {
  return Error{Error::Kind::usage, unavailable_message()};
}

#else

bool available() { return true; }

std::string library_version() {
  const int v = ::lsl::library_version();
  return std::to_string(v / 100) + "." + std::to_string(v % 100);
}

namespace {

using Json = nlohmann::json;
using SteadyTime = std::chrono::steady_clock;

// One reading of both clocks: the session clock read just before and just
// after the LSL clock, the LSL reading placed at their midpoint. The
// narrowest of a few tries is kept, so a preemption between the reads does
// not widen the mapping.
data::LslClockRecord read_clocks(const io::Clock& clock) {
  data::LslClockRecord best;
  best.uncertainty_ns = std::numeric_limits<std::int64_t>::max();
  for (int i = 0; i < 5; ++i) {
    const std::int64_t a = clock.now_ns();
    const double lsl_s = ::lsl::local_clock();
    const std::int64_t b = clock.now_ns();
    if ((b - a) / 2 < best.uncertainty_ns) {
      best.t_ns = a + (b - a) / 2;
      best.lsl_time_s = lsl_s;
      best.uncertainty_ns = (b - a) / 2;
    }
  }
  return best;
}

// Session clock → LSL clock through a reading (and back), anchored at the
// reading so that no large number loses its nanoseconds.
double to_lsl(const data::LslClockRecord& r, std::int64_t t_ns) {
  return r.lsl_time_s + static_cast<double>(t_ns - r.t_ns) * 1e-9;
}
std::int64_t to_session(const data::LslClockRecord& r, double lsl_s) {
  return r.t_ns + std::llround((lsl_s - r.lsl_time_s) * 1e9);
}

// A stream's description as stored: LSL's own XML less what names the
// machine or the network (DESIGN.md §7: no host names are stored) — those
// lines of its header, before <desc>, filled or empty.
std::string stored_xml(const std::string& xml) {
  static const std::array<std::string_view, 9> kDropped{"hostname", "v4address", "v6address", "uid", "session_id",
                                                         "v4data_port", "v4service_port", "v6data_port",
                                                         "v6service_port"};
  std::string out;
  bool in_desc = false;
  std::size_t from = 0;
  while (from < xml.size()) {
    const std::size_t to = std::min(xml.find('\n', from), xml.size());
    const std::string_view line(xml.data() + from, to - from);
    const auto text = line.substr(std::min(line.find_first_not_of(" \t"), line.size()));
    if (text.starts_with("<desc")) in_desc = true;
    const bool dropped = !in_desc && std::any_of(kDropped.begin(), kDropped.end(), [&](std::string_view tag) {
      return text.starts_with("<" + std::string(tag) + ">") || text.starts_with("<" + std::string(tag) + " ") ||
             text.starts_with("<" + std::string(tag) + "/");
    });
    if (!dropped) {
      out += line;
      if (to < xml.size()) out += '\n';
    }
    from = to + 1;
  }
  return out;
}

std::string format_name(::lsl::channel_format_t f) {
  switch (f) {
    case ::lsl::cf_float32: return "float32";
    case ::lsl::cf_double64: return "double64";
    case ::lsl::cf_string: return "string";
    case ::lsl::cf_int32: return "int32";
    case ::lsl::cf_int16: return "int16";
    case ::lsl::cf_int8: return "int8";
    case ::lsl::cf_int64: return "int64";
    default: return "undefined";
  }
}

// The poses stream: per device its position (m), orientation (x y z w) and
// tracking (2 position and orientation, 1 orientation only, 0 none).
constexpr std::array<const char*, 3> kDevices{"head", "left_hand", "right_hand"};
constexpr int kPoseChannelsPerDevice = 8;
constexpr int kPoseChannels = 3 * kPoseChannelsPerDevice;
// The gaze stream: combined ray (tracked, origin, direction), each eye's
// (tracked, confidence, origin, direction), the vergence (rad).
constexpr int kGazeChannels = 7 + 8 + 8 + 1;

void add_channel(::lsl::xml_element channels, const std::string& label, const char* unit, const char* type,
                 const char* object) {
  auto c = channels.append_child("channel");
  c.append_child_value("label", label).append_child_value("unit", unit).append_child_value("type", type);
  if (object != nullptr) c.append_child_value("object", object);
}

void add_lab_frame(::lsl::xml_element desc) {
  desc.append_child("reference")
      .append_child_value("frame", "lab")
      .append_child_value("description",
                          "the lab's floor-level frame (OpenXR STAGE): metres, x right, y up, -z forward; "
                          "quaternions x y z w");
  desc.append_child("acquisition").append_child_value("manufacturer", "curvlab");
}

::lsl::stream_info pose_info(const std::string& uuid, double rate_hz) {
  ::lsl::stream_info info("curvlab poses", "MoCap", kPoseChannels, rate_hz, ::lsl::cf_float32,
                          "curvlab-" + uuid + "-poses");
  auto channels = info.desc().append_child("channels");
  for (const char* d : kDevices) {
    const std::string p(d);
    add_channel(channels, p + "_x", "meters", "PositionX", d);
    add_channel(channels, p + "_y", "meters", "PositionY", d);
    add_channel(channels, p + "_z", "meters", "PositionZ", d);
    add_channel(channels, p + "_qx", "normalized", "OrientationX", d);
    add_channel(channels, p + "_qy", "normalized", "OrientationY", d);
    add_channel(channels, p + "_qz", "normalized", "OrientationZ", d);
    add_channel(channels, p + "_qw", "normalized", "OrientationW", d);
    add_channel(channels, p + "_tracked", "2 position and orientation, 1 orientation only, 0 none", "Tracking", d);
  }
  add_lab_frame(info.desc());
  info.desc().append_child_value("session_uuid", uuid);
  return info;
}

::lsl::stream_info gaze_info(const std::string& uuid, double rate_hz) {
  ::lsl::stream_info info("curvlab gaze", "Gaze", kGazeChannels, rate_hz, ::lsl::cf_float32,
                          "curvlab-" + uuid + "-gaze");
  auto channels = info.desc().append_child("channels");
  auto ray = [&](const std::string& p, bool confidence) {
    add_channel(channels, p + "_tracked", "1 tracked, 0 not", "Tracking", p.c_str());
    if (confidence) add_channel(channels, p + "_confidence", "0-1", "Confidence", p.c_str());
    add_channel(channels, p + "_origin_x", "meters", "PositionX", p.c_str());
    add_channel(channels, p + "_origin_y", "meters", "PositionY", p.c_str());
    add_channel(channels, p + "_origin_z", "meters", "PositionZ", p.c_str());
    add_channel(channels, p + "_direction_x", "normalized", "DirectionX", p.c_str());
    add_channel(channels, p + "_direction_y", "normalized", "DirectionY", p.c_str());
    add_channel(channels, p + "_direction_z", "normalized", "DirectionZ", p.c_str());
  };
  ray("combined", false);
  ray("left_eye", true);
  ray("right_eye", true);
  add_channel(channels, "vergence", "radians", "Vergence", nullptr);
  add_lab_frame(info.desc());
  info.desc().append_child_value("session_uuid", uuid);
  return info;
}

::lsl::stream_info marker_info(const std::string& uuid, std::int64_t session_id) {
  ::lsl::stream_info info("curvlab markers", "Markers", 1, ::lsl::IRREGULAR_RATE, ::lsl::cf_string,
                          "curvlab-" + uuid + "-markers");
  auto channels = info.desc().append_child("channels");
  add_channel(channels, "event", "JSON object: event, trial_id, detail (docs/lsl.md)", "Marker", nullptr);
  info.desc().append_child_value("session_uuid", uuid);
  info.desc().append_child_value("session_id", std::to_string(session_id));
  return info;
}

// A stream another instrument sends, resolved and subscribed before the
// session starts.
struct Recorded {
  std::string asked;  // --lsl-record's NAME_OR_TYPE
  ::lsl::stream_info info;
  std::unique_ptr<::lsl::stream_inlet> inlet;
  bool strings = false;
  std::int64_t row = 0;  // lsl_streams
};

// What the frame thread hands the outlets' thread.
struct Item {
  enum class Kind { marker, poses, gaze } kind = Kind::marker;
  std::int64_t t_ns = 0;
  std::string text;
  std::array<float, 24> values{};
};
static_assert(kPoseChannels <= 24 && kGazeChannels <= 24);

float tracked(const geometry::LabPose& p) {
  return p.valid ? 2.0F : (p.orientation_valid ? 1.0F : 0.0F);
}

void put_ray(std::array<float, 24>& v, std::size_t& k, const std::optional<io::GazeRay>& r, bool confidence) {
  const io::GazeRay ray = r.value_or(io::GazeRay{});
  v[k++] = r && ray.valid ? 1.0F : 0.0F;
  if (confidence) v[k++] = static_cast<float>(ray.confidence.value_or(-1.0));
  for (int i = 0; i < 3; ++i) v[k++] = static_cast<float>(ray.origin_m[i]);
  for (int i = 0; i < 3; ++i) v[k++] = static_cast<float>(ray.direction[i]);
}

// Owns the outlets, the recorded streams' inlets and the threads that
// serve them: one that pushes what the frame thread queued and measures the
// clocks, one per recorded stream. The frame thread only copies into a
// bounded queue under a mutex held for the copy (no I/O, no allocation for
// poses once the queue has grown to its size); when the queue is full the
// item is dropped and counted (reported at the end).
class LslStreams final : public io::SessionStreams {
 public:
  LslStreams(StreamOptions options, const io::Clock& clock, std::vector<Recorded> recorded)
      : options_(std::move(options)), clock_(clock), recorded_(std::move(recorded)) {
    pending_.reserve(kQueueCapacity);
    taken_.reserve(kQueueCapacity);
  }

  ~LslStreams() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
    if (dropped_ > 0)
      std::cerr << "curvlab: lsl: " << dropped_ << " samples were not streamed (the outlets' queue was full)\n";
    if (!log_error_.empty()) std::cerr << "curvlab: lsl: " << log_error_ << '\n';
  }

  Result<Done> start(const io::StreamedSession& s) override {
    if (log_) return Done{};
    auto log = data::StreamLog::open(s.db_path);
    if (!log) return log.error();
    log_ = std::move(log).value();
    auto uuid = log_->session_uuid(s.session_id);
    if (!uuid) return uuid.error();
    session_id_ = s.session_id;
    rate_hz_ = s.refresh_hz;
    uuid_ = uuid.value();
    if (auto ok = measure(); !ok) return ok.error();
    try {
      if (options_.outlets) {
        markers_ = std::make_unique<::lsl::stream_outlet>(marker_info(uuid_, s.session_id));
        poses_ = std::make_unique<::lsl::stream_outlet>(pose_info(uuid_, rate_hz_));
        if (auto ok = register_outlet(*markers_); !ok) return ok.error();
        if (auto ok = register_outlet(*poses_); !ok) return ok.error();
      }
      for (auto& r : recorded_) {
        auto row = log_->add_stream(record_of(data::LslRole::recorded, r.info));
        if (!row) return row.error();
        r.row = row.value();
      }
    } catch (const std::exception& e) {
      return Error{Error::Kind::device, std::string("lsl: cannot open the session's streams: ") + e.what()};
    }
    threads_.emplace_back([this] { serve_outlets(); });
    for (auto& r : recorded_) threads_.emplace_back([this, &r] { record(r); });
    if (options_.wait_for_recorder.count() > 0 && markers_) wait_for_recorder();
    return Done{};
  }

  void marker(std::int64_t t_ns, std::string text) override {
    if (!markers_) return;
    Item item;
    item.kind = Item::Kind::marker;
    item.t_ns = t_ns;
    item.text = std::move(text);
    enqueue(std::move(item));
  }

  void frame(std::int64_t display_ns, const geometry::LabFrame& lab, const std::optional<io::Gaze>& gaze) override {
    if (!poses_) return;
    Item item;
    item.kind = Item::Kind::poses;
    item.t_ns = display_ns;
    std::size_t k = 0;
    for (const auto& p : lab.pose) {
      for (int i = 0; i < 3; ++i) item.values[k++] = static_cast<float>(p.position_m[i]);
      item.values[k++] = static_cast<float>(p.orientation.x);
      item.values[k++] = static_cast<float>(p.orientation.y);
      item.values[k++] = static_cast<float>(p.orientation.z);
      item.values[k++] = static_cast<float>(p.orientation.w);
      item.values[k++] = tracked(p);
    }
    enqueue(std::move(item));
    if (!gaze) return;
    Item g;
    g.kind = Item::Kind::gaze;
    g.t_ns = display_ns;
    k = 0;
    put_ray(g.values, k, gaze->combined, false);
    put_ray(g.values, k, gaze->eyes ? std::optional((*gaze->eyes)[0]) : std::nullopt, true);
    put_ray(g.values, k, gaze->eyes ? std::optional((*gaze->eyes)[1]) : std::nullopt, true);
    g.values[k++] = gaze->vergence ? static_cast<float>(gaze->vergence->angle_rad) : 0.0F;
    enqueue(std::move(g));
  }

 private:
  static constexpr std::size_t kQueueCapacity = 4096;

  data::LslStreamRecord record_of(data::LslRole role, const ::lsl::stream_info& info) const {
    data::LslStreamRecord r;
    r.session_id = session_id_;
    r.role = role;
    r.name = info.name();
    r.type = info.type();
    r.source_id = info.source_id();
    r.channel_count = info.channel_count();
    r.nominal_srate_hz = info.nominal_srate();
    r.channel_format = format_name(info.channel_format());
    r.info_xml = stored_xml(info.as_xml());
    return r;
  }

  Result<Done> register_outlet(::lsl::stream_outlet& outlet) {
    auto row = log_->add_stream(record_of(data::LslRole::outlet, outlet.info()));
    if (!row) return row.error();
    return Done{};
  }

  // Each outlet's first recorder: LabRecorder's or a test's inlet, so that
  // the session's first marker is recorded too.
  void wait_for_recorder() {
    const auto until = SteadyTime::now() + options_.wait_for_recorder;
    auto left = [&] { return std::chrono::duration<double>(until - SteadyTime::now()).count(); };
    bool all = markers_->wait_for_consumers(std::max(0.0, left()));
    all = poses_->wait_for_consumers(std::max(0.0, left())) && all;
    if (!all)
      std::cerr << "curvlab: lsl: no recorder connected to the session's streams within "
                << std::chrono::duration<double>(options_.wait_for_recorder).count() << " s; streaming without one\n";
  }

  void enqueue(Item&& item) {
    {
      std::lock_guard lock(mutex_);
      if (pending_.size() >= kQueueCapacity) {
        ++dropped_;
        return;
      }
      pending_.push_back(std::move(item));
    }
    wake_.notify_one();
  }

  Result<Done> measure() {
    const auto r = read_clocks(clock_);
    {
      std::lock_guard lock(clock_mutex_);
      reading_ = r;
    }
    data::LslClockRecord stored = r;
    stored.session_id = session_id_;
    auto ok = log_->add_clock(stored);
    if (!ok) return ok.error();
    return Done{};
  }

  data::LslClockRecord reading() const {
    std::lock_guard lock(clock_mutex_);
    return reading_;
  }

  // The outlets' thread: pushes what the frame thread queued, each sample
  // with the LSL time of the moment it describes, and measures the clocks
  // again every clock_interval.
  void serve_outlets() {
    auto next_measure = SteadyTime::now() + options_.clock_interval;
    for (;;) {
      {
        std::unique_lock lock(mutex_);
        wake_.wait_until(lock, next_measure, [this] { return stopping_ || !pending_.empty(); });
        taken_.swap(pending_);
        if (stopping_ && taken_.empty()) return;
      }
      if (SteadyTime::now() >= next_measure) {
        if (auto ok = measure(); !ok) note_error(ok.error().message);
        next_measure = SteadyTime::now() + options_.clock_interval;
      }
      push_taken();
    }
  }

  void push_taken() {
    const auto r = reading();
    for (Item& item : taken_) {
      const double t = to_lsl(r, item.t_ns);
      try {
        switch (item.kind) {
          case Item::Kind::marker: markers_->push_sample(&item.text, t); break;
          case Item::Kind::poses: poses_->push_sample(item.values.data(), t); break;
          case Item::Kind::gaze:
            if (!gaze_) open_gaze();
            gaze_->push_sample(item.values.data(), t);
            break;
        }
      } catch (const std::exception& e) {
        note_error(std::string("cannot push a sample: ") + e.what());
      }
    }
    taken_.clear();
  }

  void open_gaze() {
    gaze_ = std::make_unique<::lsl::stream_outlet>(gaze_info(uuid_, rate_hz_));
    if (auto ok = register_outlet(*gaze_); !ok) note_error(ok.error().message);
  }

  void note_error(const std::string& message) {
    std::lock_guard lock(error_mutex_);
    if (log_error_.empty()) log_error_ = message;
  }

  bool stopping() {
    std::lock_guard lock(mutex_);
    return stopping_;
  }

  // One recorded stream's thread: every sample, stored with its LSL time
  // stamp, the sender's clock offset (time_correction, measured again every
  // clock_interval) and the session-clock time both map to.
  void record(Recorded& r) {
    std::vector<data::LslSampleRecord> batch;
    double offset_s = 0.0;
    auto next_correction = SteadyTime::now();
    auto last_flush = SteadyTime::now();
    std::vector<std::string> strings;
    std::vector<double> numbers;
    auto flush = [&] {
      if (auto ok = log_->add_samples(batch); !ok) note_error(ok.error().message);
      batch.clear();
      last_flush = SteadyTime::now();
    };
    while (!stopping()) {
      try {
        if (SteadyTime::now() >= next_correction) {
          offset_s = r.inlet->time_correction(1.0);
          next_correction = SteadyTime::now() + options_.clock_interval;
        }
        const double ts = r.strings ? r.inlet->pull_sample(strings, 0.05) : r.inlet->pull_sample(numbers, 0.05);
        if (ts != 0.0) {
          data::LslSampleRecord s;
          s.lsl_stream_id = r.row;
          s.received_ns = clock_.now_ns();
          s.lsl_time_s = ts;
          s.lsl_offset_s = offset_s;
          s.t_ns = to_session(reading(), ts + offset_s);
          s.value_json = r.strings ? Json(strings).dump() : Json(numbers).dump();
          batch.push_back(std::move(s));
        }
      } catch (const ::lsl::timeout_error&) {
        next_correction = SteadyTime::now() + std::chrono::seconds(1);
      } catch (const std::exception& e) {
        note_error("stream '" + r.asked + "': " + e.what());
      }
      if (!batch.empty() && (batch.size() >= 256 || SteadyTime::now() - last_flush >= std::chrono::milliseconds(200)))
        flush();
    }
    // What arrived before the session ended.
    try {
      for (double ts = 1.0; ts != 0.0;) {
        ts = r.strings ? r.inlet->pull_sample(strings, 0.0) : r.inlet->pull_sample(numbers, 0.0);
        if (ts == 0.0) break;
        data::LslSampleRecord s;
        s.lsl_stream_id = r.row;
        s.received_ns = clock_.now_ns();
        s.lsl_time_s = ts;
        s.lsl_offset_s = offset_s;
        s.t_ns = to_session(reading(), ts + offset_s);
        s.value_json = r.strings ? Json(strings).dump() : Json(numbers).dump();
        batch.push_back(std::move(s));
      }
    } catch (const std::exception& e) {
      note_error("stream '" + r.asked + "': " + e.what());
    }
    flush();
  }

  StreamOptions options_;
  const io::Clock& clock_;
  std::vector<Recorded> recorded_;
  std::unique_ptr<data::StreamLog> log_;
  std::int64_t session_id_ = 0;
  double rate_hz_ = 90.0;
  std::string uuid_;
  std::unique_ptr<::lsl::stream_outlet> markers_;
  std::unique_ptr<::lsl::stream_outlet> poses_;
  std::unique_ptr<::lsl::stream_outlet> gaze_;  // opened with the first gaze sample

  mutable std::mutex clock_mutex_;
  data::LslClockRecord reading_;

  std::mutex mutex_;  // guards pending_, stopping_, dropped_
  std::condition_variable wake_;
  std::vector<Item> pending_;
  std::vector<Item> taken_;  // the outlets' thread's only
  bool stopping_ = false;
  std::uint64_t dropped_ = 0;

  std::mutex error_mutex_;
  std::string log_error_;
  std::vector<std::thread> threads_;
};

// XPath's string literal for `text`, or nullopt when it holds both quotes.
std::optional<std::string> xpath_literal(const std::string& text) {
  if (text.find('\'') == std::string::npos) return "'" + text + "'";
  if (text.find('"') == std::string::npos) return "\"" + text + "\"";
  return std::nullopt;
}

Result<Recorded> resolve(const std::string& asked, std::chrono::milliseconds timeout) {
  if (asked.empty()) return Error{Error::Kind::usage, "--lsl-record: a stream's name or type is empty"};
  const auto literal = xpath_literal(asked);
  if (!literal) return Error{Error::Kind::usage, "--lsl-record " + asked + ": a name holds both kinds of quote"};
  const double seconds = std::chrono::duration<double>(timeout).count();
  try {
    auto found = ::lsl::resolve_stream("name=" + *literal + " or type=" + *literal, 1, seconds);
    if (found.empty()) {
      char waited[32];
      std::snprintf(waited, sizeof waited, "%.3g s", seconds);
      return Error{Error::Kind::device, "--lsl-record " + asked + ": no Lab Streaming Layer stream named or typed '" +
                                            asked + "' was found within " + waited +
                                            "; start the program that sends it first (LabRecorder lists the "
                                            "streams it sees), or check LSLAPICFG's network settings"};
    }
    Recorded r;
    r.asked = asked;
    r.inlet = std::make_unique<::lsl::stream_inlet>(found.front(), 360, 0, true);
    r.inlet->open_stream(seconds);
    r.info = r.inlet->info(seconds);
    r.strings = r.info.channel_format() == ::lsl::cf_string;
    return r;
  } catch (const std::exception& e) {
    return Error{Error::Kind::device, "--lsl-record " + asked + ": cannot subscribe to the stream: " + e.what()};
  }
}

}  // namespace

Result<std::unique_ptr<io::SessionStreams>> open(const StreamOptions& options, const io::Clock& clock) {
  std::vector<Recorded> recorded;
  for (const auto& asked : options.record) {
    auto r = resolve(asked, options.resolve_timeout);
    if (!r) return r.error();
    recorded.push_back(std::move(r).value());
  }
  return std::unique_ptr<io::SessionStreams>(std::make_unique<LslStreams>(options, clock, std::move(recorded)));
}

#endif

}  // namespace curvlab::harness::lsl
