#include "curvlab/harness/protocol/protocol.hpp"

#include "curvlab/geometry/table.hpp"

namespace curvlab::harness::protocol {

std::string_view to_string(RandomizeMode m) {
  switch (m) {
    case RandomizeMode::none: return "none";
    case RandomizeMode::shuffle: return "shuffle";
    case RandomizeMode::shuffle_within_repetition: return "shuffle_within_repetition";
  }
  return "?";
}

std::string_view to_string(BlockOrder o) {
  switch (o) {
    case BlockOrder::fixed: return "fixed";
    case BlockOrder::latin_square: return "latin_square";
    case BlockOrder::random: return "random";
  }
  return "?";
}

namespace {
void apply_all(Settings& s, const std::vector<SettingOverride>& overrides) {
  for (const auto& o : overrides)
    if (const auto* info = find_setting(o.path)) apply_setting(s, *info, o.value);
}
}  // namespace

Settings Protocol::session_settings() const {
  Settings s;
  apply_all(s, session_overrides);
  return s;
}

Settings Protocol::block_settings(const Block& b) const {
  Settings s = session_settings();
  apply_all(s, b.overrides);
  return s;
}

const Factor* Protocol::find_factor(const std::string& name) const {
  for (const auto& f : factors)
    if (f.name == name) return &f;
  return nullptr;
}

Result<geometry::TableShape> table_shape(const Settings& s) {
  const auto kind = s.space.kind;
  const int sides = s.space.table_sides > 0 ? s.space.table_sides : geometry::default_table_sides(kind);
  std::variant<geometry::TableShape, geometry::GeometryError> shape;
  if (s.space.radius_m && kind != geometry::SpaceKind::E3) {
    // A fixed radius: the virtual edge is whatever fits 90° corners.
    shape = geometry::right_angled_table_from_radius(geometry::Space{kind, *s.space.radius_m}, sides);
  } else {
    const double e3_radius = s.space.radius_m.value_or(s.space.e3_radius_m);
    shape = geometry::right_angled_table_from_edge(kind, s.table.edge_m, sides, e3_radius);
  }
  if (const auto* err = std::get_if<geometry::GeometryError>(&shape))
    return Error{Error::Kind::bad_input, err->message};
  return std::get<geometry::TableShape>(shape);
}

Result<Derived> derive(const Settings& s) {
  auto shape = table_shape(s);
  if (!shape) return shape.error();
  const auto& t = shape.value();
  Derived d;
  d.radius_m = t.radius_m;
  d.table_sides = t.sides;
  d.side_rad = t.side_rad;
  d.table_circumradius_m = t.circumradius_m();
  d.table_apothem_m = t.apothem_m();
  return d;
}

}  // namespace curvlab::harness::protocol
