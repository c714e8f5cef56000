#pragma once
// A Newton step of the static equilibrium applied along arcs. The step is linear in each
// body's translation and rotation: a body that turns by phi about its centre, while its
// centre moves along the tangent, leaves the point where it hangs off by the rotation's
// second-order term, |phi|^2 r / 2. A stiff bushing turns that into forces far above the
// residual (a body at 0.5 m on 1e5 N/m, turned by 0.4 rad: 4 000 N against its 10 N
// weight), so the next step is spent undoing it and steps stay short.
//
// ArcStep moves each body's centre further, by the least (stiffness-weighted) amount that
// gives every bushing and compliant joint the deflection the linear step predicted: the
// turn happens about where the body is held. The corrections d solve a weighted graph
// Laplacian L d = r (one row per free body, one term per connection), factored once: on a
// tree (a chain) the joints close exactly and the whole chain swings about its pivot.
// Rigid joints are left to the equilibrium's own projection (settle_on_joints), which
// may also turn the bodies: pulling a chain of rigid links shut from its pivot alone made a
// 60-link revolute chain released level take 101 iterations instead of 17.
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <vector>

#include "mbsflow/analysis/linearization.hpp"

namespace mbsflow {

class ArcStep {
 public:
  ArcStep(const Model& model, const FreeCoordinates& coords);
  ArcStep(const ArcStep&) = delete;
  ArcStep& operator=(const ArcStep&) = delete;
  // y (the state the step starts from) moved by the tangent step dx, as apply_tangent_step
  // does, with each free body's centre moved further by its arc correction.
  void apply(const StateLayout& l, const Eigen::VectorXd& dx, Eigen::VectorXd& y) const;

 private:
  struct Connection {
    int a, b;                // free-body indices of the two sides (-1: ground or held)
    double weight;           // the translational stiffness
    Eigen::Vector3d pa, pb;  // the attachment points in the bodies' frames
  };
  const FreeCoordinates& coords_;
  std::vector<Connection> connections_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> laplacian_;
};

}  // namespace mbsflow
