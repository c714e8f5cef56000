// The "beams" of a model file (docs/beams.md): each one's fields, checked and named as a
// body's are, turned into its node bodies and element bushings (graph/beams.hpp).
#include "beam_reader.hpp"

#include <cmath>
#include <numbers>

#include "mbsflow/error.hpp"
#include "model_fields.hpp"

namespace mbsflow {

BeamParts read_beam(const JsonNode& n, int first_body, std::string& name) {
  using model_fields::vec3;
  n.allow_only({"name", "from", "to", "elements", "points", "up", "E", "G", "density", "section", "shear", "damping"});
  BeamSpec s;
  const JsonNode name_node = n["name"];
  s.name = name_node.string();
  if (s.name.empty()) name_node.fail("must not be empty");
  if (s.name.find('.') != std::string::npos) name_node.fail("must not hold '.' (its nodes are NAME.0, NAME.1, ...)");
  name = s.name;
  if (auto p = n.find("points")) {
    for (const char* key : {"from", "to", "elements"})
      if (n.has(key)) n[key].fail_at_key("give either points or from/to/elements, not both");
    const std::size_t count = p->array_size();
    if (count < 2) p->fail("must list at least 2 points (one element)");
    for (std::size_t i = 0; i < count; ++i) s.points.push_back(p->item(i).fixed<3>());
  } else {
    const long elements = n["elements"].integer(1, 10'000'000);
    s.points = straight_beam_points(n["from"].fixed<3>(), n["to"].fixed<3>(), static_cast<int>(elements));
  }
  s.up = vec3(n, "up", Vec3{0.0, 1.0, 0.0});
  s.E = n["E"].positive();
  s.G = n["G"].positive();
  s.density = n["density"].positive();
  const JsonNode sec = n["section"];
  sec.allow_only({"area", "Iy", "Iz", "J", "shear_area_y", "shear_area_z"});
  s.section.area = sec["area"].positive();
  s.section.Iy = sec["Iy"].positive();
  s.section.Iz = sec["Iz"].positive();
  s.section.J = sec["J"].positive();
  if (auto v = sec.find("shear_area_y")) s.section.shear_area_y = v->positive();
  if (auto v = sec.find("shear_area_z")) s.section.shear_area_z = v->positive();
  if (auto v = n.find("shear")) s.shear = v->boolean();
  if (auto d = n.find("damping")) {
    // Stiffness-proportional: beta directly, or the damping ratio at a frequency (zeta =
    // beta omega / 2 there, rising with frequency); and Rayleigh's mass-proportional alpha.
    d->allow_only({"beta", "ratio", "frequency", "alpha"});
    if (auto b = d->find("beta")) {
      if (d->has("ratio")) (*d)["ratio"].fail_at_key("give either beta or ratio with frequency, not both");
      s.stiffness_damping = b->non_negative();
    } else if (d->has("ratio") || d->has("frequency") || !d->has("alpha")) {
      const double ratio = (*d)["ratio"].non_negative(), f = (*d)["frequency"].positive();
      s.stiffness_damping = 2.0 * ratio / (2.0 * std::numbers::pi * f);
    }
    if (auto a = d->find("alpha")) s.mass_damping = a->non_negative();
  }
  try {
    return make_beam(s, first_body);
  } catch (const InputError& e) {  // geometry: along the axis, coinciding points
    const std::string what = e.what();
    if (what.find("up is parallel") != std::string::npos) (n.find("up") ? n["up"] : n).fail(what);
    (n.find("points") ? n["points"] : n).fail(what);
  }
}

}  // namespace mbsflow
