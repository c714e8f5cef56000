#include "mbsflow/graph/generators.hpp"

#include <cmath>
#include <random>
#include <string>

#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

Vec6 box_inertia(double m, double lx, double ly, double lz) {
  return {m * (ly * ly + lz * lz) / 12.0, m * (lx * lx + lz * lz) / 12.0, m * (lx * lx + ly * ly) / 12.0, 0, 0, 0};
}

Body body(ValueSharing& shared, std::string name, double mass, Vec6 inertia, Vec3 position, Vec3 velocity = {}) {
  Body b;
  b.name = std::move(name);
  b.mass = mass;
  b.inertia = inertia;
  b.position = position;
  b.velocity = velocity;
  shared(b);
  return b;
}

// Bushing with per-axis stiffness; damping from a damping ratio on each axis with the
// joined reduced mass (translation) or reduced inertia (rotation). Its values are shared
// with the generator's joints before it where they repeat (ValueSharing).
Joint bushing(const Model& m, ValueSharing& shared, std::string name, int b1, int b2, Vec3 p1, Vec3 p2, Vec6 k, double zeta) {
  Joint j;
  j.name = std::move(name);
  j.body1 = b1;
  j.body2 = b2;
  j.point1 = p1;
  j.point2 = p2;
  j.stiffness = k;
  Vec6 c;
  for (std::size_t a = 0; a < 6; ++a) {
    const std::size_t ia = a < 3 ? 0 : a - 3;
    auto inert = [&](int b) { return a < 3 ? m.bodies[static_cast<std::size_t>(b)].mass
                                           : m.bodies[static_cast<std::size_t>(b)].inertia[ia]; };
    const double x2 = inert(b2);
    const double red = b1 == ground ? x2 : inert(b1) * x2 / (inert(b1) + x2);
    c[a] = 2.0 * zeta * std::sqrt(k[a] * red);
  }
  j.damping = c;
  shared(j);
  return j;
}

void require(bool ok, const char* what) {
  if (!ok) throw InputError(what);
}

}  // namespace

Model make_chain(const ChainParams& p) {
  require(p.bodies >= 1, "chain: {bodies} must be >= 1");
  Model m;
  ValueSharing shared;
  m.name = "chain-" + std::to_string(p.bodies);
  m.gravity = {0.0, -9.81, 0.0};
  const double l = p.link_length, r = 0.1 * l;
  const Vec6 inertia{0.5 * p.mass * r * r, p.mass * l * l / 12.0, p.mass * l * l / 12.0, 0, 0, 0};
  const Vec6 k{p.stiffness, p.stiffness, p.stiffness, p.rotational_stiffness, p.rotational_stiffness,
               p.rotational_stiffness};
  for (int i = 0; i < p.bodies; ++i) m.bodies.push_back(body(shared, "link" + std::to_string(i), p.mass, inertia, {(i + 0.5) * l, 0, 0}));
  m.joints.push_back(bushing(m, shared, "pin", ground, 0, {0, 0, 0}, {-0.5 * l, 0, 0}, k, p.damping_ratio));
  for (int i = 1; i < p.bodies; ++i)
    m.joints.push_back(bushing(m, shared, "j" + std::to_string(i), i - 1, i, {0.5 * l, 0, 0}, {-0.5 * l, 0, 0}, k, p.damping_ratio));
  m.simulation.t_end = 1.0;
  m.simulation.output_every = 100;
  return m;
}

Model make_grid(const GridParams& p) {
  require(p.rows >= 1 && p.cols >= 1, "grid: {rows} and {cols} must be >= 1");
  Model m;
  ValueSharing shared;
  m.name = "grid-" + std::to_string(p.rows) + "x" + std::to_string(p.cols);
  m.gravity = {0.0, -9.81, 0.0};
  const double s = p.spacing;
  const Vec6 inertia = box_inertia(p.mass, s, 0.1 * s, s);
  const Vec6 k{p.stiffness, p.stiffness, p.stiffness, p.rotational_stiffness, p.rotational_stiffness,
               p.rotational_stiffness};
  auto id = [&](int r, int c) { return r * p.cols + c; };
  for (int r = 0; r < p.rows; ++r)
    for (int c = 0; c < p.cols; ++c)
      m.bodies.push_back(body(shared, "p" + std::to_string(r) + "_" + std::to_string(c), p.mass, inertia, {(c + 0.5) * s, 0, r * s}));
  const double h = 0.5 * s;
  for (int r = 0; r < p.rows; ++r) {
    m.joints.push_back(bushing(m, shared, "clamp" + std::to_string(r), ground, id(r, 0), {0, 0, r * s}, {-h, 0, 0}, k, p.damping_ratio));
    for (int c = 0; c < p.cols; ++c) {
      const std::string tag = std::to_string(r) + "_" + std::to_string(c);
      if (c + 1 < p.cols) m.joints.push_back(bushing(m, shared, "x" + tag, id(r, c), id(r, c + 1), {h, 0, 0}, {-h, 0, 0}, k, p.damping_ratio));
      if (r + 1 < p.rows) m.joints.push_back(bushing(m, shared, "z" + tag, id(r, c), id(r + 1, c), {0, 0, h}, {0, 0, -h}, k, p.damping_ratio));
    }
  }
  m.simulation.t_end = 1.0;
  m.simulation.output_every = 100;
  return m;
}

Model make_train(const TrainParams& p) {
  require(p.wagons >= 1, "train: {wagons} must be >= 1");
  Model m;
  ValueSharing shared;
  m.name = "train-" + std::to_string(p.wagons);
  const double g = 9.81;
  m.gravity = {0.0, -g, 0.0};
  const double car_mass = 40000, bogie_mass = 3000, wheelset_mass = 1500;
  const double pitch = 22.0, car_half = 10.5, bogie_x = 7.0, axle_x = 1.25;
  const double y_wheel = 0.46, y_bogie = 0.8, y_car = 2.0;
  const Vec3 v{p.speed, 0, 0};
  const Vec6 primary{1e7, 1.2e6, 5e6, 1e5, 1e5, 1e5};
  const Vec6 secondary{4e5, 6e5, 2e5, 2e5, 2e5, 2e5};
  const Vec6 coupler{5e6, 1e6, 1e6, 1e5, 1e5, 1e5};
  const double primary_load = 0.5 * (0.5 * car_mass + bogie_mass) * g;  // per wheelset
  const double secondary_load = 0.5 * car_mass * g;                    // per bogie
  for (int w = 0; w < p.wagons; ++w) {
    const std::string tag = std::to_string(w);
    const double x0 = -w * pitch;
    const int car = static_cast<int>(m.bodies.size());
    m.bodies.push_back(body(shared, "car" + tag, car_mass, box_inertia(car_mass, 2 * car_half, 3.0, 3.0), {x0, y_car, 0}, v));
    for (int s = 0; s < 2; ++s) {
      const double bx = s == 0 ? bogie_x : -bogie_x;
      const std::string btag = tag + (s == 0 ? "f" : "r");
      const int bogie = static_cast<int>(m.bodies.size());
      m.bodies.push_back(body(shared, "bogie" + btag, bogie_mass, box_inertia(bogie_mass, 3.0, 0.8, 2.5), {x0 + bx, y_bogie, 0}, v));
      Joint sec = bushing(m, shared, "secondary" + btag, bogie, car, {0, 0.3, 0}, {bx, y_bogie + 0.3 - y_car, 0}, secondary, 0.2);
      sec.preload = {0, secondary_load, 0, 0, 0, 0};
      m.joints.push_back(sec);
      for (int a = 0; a < 2; ++a) {
        const double ax = a == 0 ? axle_x : -axle_x;
        const int ws = static_cast<int>(m.bodies.size());
        const double x = x0 + bx + ax;
        m.bodies.push_back(body(shared, "wheelset" + btag + std::to_string(a), wheelset_mass,
                                box_inertia(wheelset_mass, 0.9, 0.9, 2.0), {x, y_wheel, 0}, v));
        Driver d;
        d.body = ws;
        d.velocity = v;
        // The same track under every wheelset, reached x/speed seconds later or earlier.
        d.displacement[1] = TimeFunction::random(p.vertical_roughness, 10.0, p.seed, 48);
        d.displacement[2] = TimeFunction::random(p.lateral_roughness, 5.0, p.seed + 7919u, 48);
        d.displacement[1].delay = d.displacement[2].delay = -x / p.speed;
        m.drivers.push_back(d);
        Joint pri = bushing(m, shared, "primary" + btag + std::to_string(a), ws, bogie, {0, 0, 0}, {ax, y_wheel - y_bogie, 0},
                            primary, 0.1);
        pri.preload = {0, primary_load, 0, 0, 0, 0};
        m.joints.push_back(pri);
      }
    }
    if (w > 0)
      m.joints.push_back(bushing(m, shared, "coupler" + tag, car - 7, car, {-0.5 * (pitch), 0, 0}, {0.5 * pitch, 0, 0}, coupler, 0.1));
  }
  m.simulation.t_end = 2.0;
  m.simulation.output_every = 10;
  return m;
}

Model make_random_tree(const RandomTreeParams& p) {
  require(p.bodies >= 1, "random: {bodies} must be >= 1");
  require(p.cycles >= 0, "random: {cycles} must be >= 0");
  Model m;
  ValueSharing shared;
  m.name = "random-" + std::to_string(p.bodies) + "-" + std::to_string(p.cycles);
  m.gravity = {0.0, -9.81, 0.0};
  std::mt19937_64 rng(p.seed);  // its raw output is the same everywhere
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  auto index = [&](int n) { return static_cast<int>(rng() % static_cast<std::uint64_t>(n)); };
  const double mass = 1.0, len = 0.2;
  const Vec6 inertia = box_inertia(mass, 0.1, 0.1, 0.1);
  const Vec6 k{1e5, 1e5, 1e5, 50, 50, 50};
  // A joint at the midpoint of two bodies, unstressed in the initial configuration.
  auto join = [&](std::string name, int a, int b) {
    const Vec3& ra = m.bodies[static_cast<std::size_t>(a)].position;
    const Vec3& rb = m.bodies[static_cast<std::size_t>(b)].position;
    const Vec3 mid{0.5 * (ra[0] + rb[0]), 0.5 * (ra[1] + rb[1]), 0.5 * (ra[2] + rb[2])};
    m.joints.push_back(bushing(m, shared, std::move(name), a, b, {mid[0] - ra[0], mid[1] - ra[1], mid[2] - ra[2]},
                               {mid[0] - rb[0], mid[1] - rb[1], mid[2] - rb[2]}, k, 0.05));
  };
  for (int i = 0; i < p.bodies; ++i) {
    Vec3 at{0.0, -len, 0.0};
    const int parent = i == 0 ? ground : index(i);
    if (parent != ground) {
      const Vec3& pp = m.bodies[static_cast<std::size_t>(parent)].position;
      const double a = 2.0 * M_PI * uniform(), z = 0.6 * uniform() - 0.3;
      at = {pp[0] + len * std::cos(a), pp[1] - len * (0.5 + 0.5 * uniform()), pp[2] + len * z};
    }
    m.bodies.push_back(body(shared, "r" + std::to_string(i), mass, inertia, at));
    if (parent == ground)
      m.joints.push_back(bushing(m, shared, "root", ground, 0, {0, 0, 0}, {0, len, 0}, k, 0.05));
    else
      join("t" + std::to_string(i), parent, i);
  }
  for (int c = 0; c < p.cycles && p.bodies > 2; ++c) {
    int a = index(p.bodies), b = index(p.bodies);
    if (a == b) b = (a + 1) % p.bodies;
    join("c" + std::to_string(c), std::min(a, b), std::max(a, b));
  }
  m.simulation.t_end = 1.0;
  m.simulation.output_every = 50;
  return m;
}

}  // namespace mbsflow
