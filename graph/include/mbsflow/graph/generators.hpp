#pragma once
// Benchmark and example models of any size.
#include "mbsflow/graph/model.hpp"

namespace mbsflow {

// A chain of rod-like links hanging from the ground at one end, released horizontally
// along +x under gravity -y; neighbours are joined by 6-axis bushings at the link ends.
struct ChainParams {
  int bodies = 100;
  double link_length = 0.1;
  double mass = 1.0;
  double stiffness = 1e6;            // translational, N/m
  double rotational_stiffness = 1.0;  // bending and torsion, N m/rad
  double damping_ratio = 0.02;       // of the translational and rotational modes
};
Model make_chain(const ChainParams& p);

// A plate of rows x cols bodies in the x-z plane, each joined to its 4 neighbours,
// the first column clamped to the ground, bending under gravity -y.
struct GridParams {
  int rows = 10, cols = 10;
  double spacing = 0.1;
  double mass = 0.5;
  double stiffness = 1e6;
  double rotational_stiffness = 200.0;
  double damping_ratio = 0.02;
};
Model make_grid(const GridParams& p);

// A train of wagons running along +x over a rough track: each wagon is a car body on
// two bogies, each bogie on two wheelsets; wheelsets follow the track (drivers with a
// band-limited random vertical and lateral profile), primary and secondary suspension
// are preloaded bushings, wagons are joined by couplers.
struct TrainParams {
  int wagons = 3;
  double speed = 30.0;             // m/s
  double vertical_roughness = 2e-3;  // rms, m
  double lateral_roughness = 1e-3;   // rms, m
  unsigned seed = 1;
};
Model make_train(const TrainParams& p);

// A random tree of bodies hanging from the ground (each body joined by a bushing to a
// random earlier one) with extra joints closing cycles; the same seed gives the same model.
struct RandomTreeParams {
  int bodies = 100;
  int cycles = 10;
  unsigned seed = 1;
};
Model make_random_tree(const RandomTreeParams& p);

}  // namespace mbsflow
