// The analytic Jacobian of a rigid cluster's rates. The right-hand side (solve_cluster in
// multibody_constraints.cpp) solves
//   S lambda = -(J A + bias),  S = J W J^T,  acc = A + W J^T lambda,
// with A the bodies' accelerations under the applied forces alone, J the constraint rows,
// W the inverse masses and world inverse inertias, and acc the accelerations (world frame).
// Along one state number y_k, with the multipliers held first,
//   g = dA + dW J^T lambda + W dJ^T lambda,
// and differentiating J acc + bias = 0 gives their change:
//   S dlambda = -(dJ acc + J g + dbias),   dacc = g + W J^T dlambda.
// dA comes from the unconstrained rates (analytic_jacobian.cpp), dJ and dbias from the
// constraint rows evaluated in dual numbers (the arithmetic the right-hand side runs), and
// each column costs a solve with the factors the right-hand side left: a cluster of n
// bodies takes 13 n of them (done 64 columns at a time) where differences take 13 n
// right-hand sides.
#include <algorithm>
#include <array>

#include "jacobian_seeds.hpp"
#include "multibody_constraints.hpp"

namespace mbsflow {
namespace {

using namespace jacobian_seeds;
using Dual4 = Eigen::AutoDiffScalar<Eigen::Vector4d>;

// Columns solved together: enough for the blocked triangular solves to pay (a body's 13
// state numbers times a few bodies), few enough that z stays small for large clusters.
constexpr int jacobian_columns_per_solve = 64;

// d R / d q_k (k = 0..3) of R = rotation_matrix(q), which normalises q.
std::array<Eigen::Matrix3d, 4> rotation_derivatives(const Eigen::Vector4d& q) {
  Vector4T<Dual4> s;
  for (int k = 0; k < 4; ++k) s[k] = Dual4(q[k], 4, k);
  const Matrix3T<Dual4> r = rotation_matrix<Dual4>(s);
  std::array<Eigen::Matrix3d, 4> d;
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) d[static_cast<std::size_t>(k)](i, j) = r(i, j).derivatives()[k];
  return d;
}

}  // namespace

void MultibodySystem::cluster_jacobian(int c, double t, const Eigen::VectorXd& y, const Eigen::VectorXd& dydt,
                                       const std::vector<RateBlocks>& unconstrained,
                                       const std::function<void(int, int, const Eigen::VectorXd&)>& column) const {
  const Constraints& k = *constraints_;
  const RigidCluster& rc = k.clusters[static_cast<std::size_t>(c)];
  const std::vector<int>& bodies = rc.bodies();
  const std::size_t nb = bodies.size();
  const Eigen::VectorXd& lambda = k.lambda[static_cast<std::size_t>(c)];
  const Eigen::Index n = layout_.bodies;
  auto free = [&](int i) { return i < n && compiled_->driver_of_body[static_cast<std::size_t>(i)] < 0; };
  auto slot_of = [&](int body) {
    const auto at = std::lower_bound(bodies.begin(), bodies.end(), body);
    return at != bodies.end() && *at == body ? static_cast<int>(at - bodies.begin()) : -1;
  };

  // Per body: its accelerations, the constraint wrench J^T lambda, and (free bodies) the
  // rotation's derivatives and the angular acceleration the applied forces alone give
  // (body frame).
  std::vector<Vector6d> acc(nb), wrench;
  rc.wrenches(lambda, wrench);
  std::vector<std::array<Eigen::Matrix3d, 4>> d_rot(nb);
  std::vector<Eigen::Vector3d> applied_rate(nb);
  for (std::size_t s = 0; s < nb; ++s) {
    const int i = bodies[s];
    const auto bi = static_cast<std::size_t>(i);
    acc[s] << dydt.segment<3>(layout_.velocity(i)), rot_[bi] * dydt.segment<3>(layout_.angular_velocity(i));
    if (!free(i)) continue;
    d_rot[s] = rotation_derivatives(y.segment<4>(layout_.orientation(i)));
    applied_rate[s] = dydt.segment<3>(layout_.angular_velocity(i)) -
                      body_law(bi).inv_inertia * (rot_[bi].transpose() * wrench[s].tail<3>());
  }

  // Per row: d (j, bias) / d (states of body a, then of body b), and per body the joints on it.
  using RowDerivatives = Eigen::Matrix<double, 13, 2 * body_states>;
  std::vector<RowDerivatives> d_row(static_cast<std::size_t>(rc.row_count()));
  std::vector<std::vector<int>> joints_on(nb);
  std::array<ConstraintRowT<Dual>, 8> rows;
  for (std::size_t q = 0; q < rc.joints().size(); ++q) {
    const ClusterJoint& cj = rc.joints()[q];
    const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
    auto frame = [&](int body, int first) {
      return free(body) ? motion(seeded_frame(y, layout_, body, first)) : constant_motion<Dual>(motion_at(body));
    };
    evaluate_constraint<Dual>(k.geometry[static_cast<std::size_t>(j.kinematic)], frame(j.a, 0), frame(j.b, body_states), t,
                              rows.data());
    for (int r = 0; r < cj.rows; ++r) {
      RowDerivatives& d = d_row[static_cast<std::size_t>(cj.first_row + r)];
      const ConstraintRowT<Dual>& row = rows[static_cast<std::size_t>(r)];
      for (int e = 0; e < 12; ++e) d.row(e) = row.j[e].derivatives().transpose();
      d.row(12) = row.bias.derivatives().transpose();
    }
    for (int side : {cj.a, cj.b})
      if (side >= 0) joints_on[static_cast<std::size_t>(side)].push_back(static_cast<int>(q));
  }

  // The free bodies whose states the cluster's rates read: its own and those its applied
  // forces read.
  std::vector<int> read(bodies.begin(), bodies.end());
  for (const RateBlocks& blocks : unconstrained)
    for (const auto& [b, m] : blocks) read.push_back(b);
  std::sort(read.begin(), read.end());
  read.erase(std::unique(read.begin(), read.end()), read.end());

  // The columns, (body, state number), in that order; a chunk of them at a time: their
  // right-hand sides z first, then one solve for all of them (blocked), then their rates.
  struct Column {
    int b, q;    // the free body and its state number
    int sb;      // b's slot in the cluster, -1 outside it
    bool turns;  // a quaternion number of a body of the cluster
  };
  std::vector<Column> columns;
  for (const int b : read) {
    if (!free(b)) continue;
    const int sb = slot_of(b);
    for (int q = 0; q < body_states; ++q) columns.push_back({b, q, sb, sb >= 0 && q >= 3 && q < 7});
  }
  const auto chunk = static_cast<std::size_t>(jacobian_columns_per_solve);
  std::vector<Vector6d> g(nb * std::min(chunk, columns.size())), nu(nb), moved;
  Eigen::MatrixXd z;
  Eigen::VectorXd rates(6 * static_cast<Eigen::Index>(nb));
  for (std::size_t first = 0; first < columns.size(); first += chunk) {
    const std::size_t count = std::min(chunk, columns.size() - first);
    z.setZero(rc.row_count(), static_cast<Eigen::Index>(count));
    for (std::size_t c = 0; c < count; ++c) {
      const auto [b, q, sb, turns] = columns[first + c];
      Vector6d* gc = g.data() + c * nb;
      std::fill(gc, gc + nb, Vector6d::Zero());
      std::fill(nu.begin(), nu.end(), Vector6d::Zero());
      auto zc = z.col(static_cast<Eigen::Index>(c));
      // dA: the applied forces' part, world frame.
      for (std::size_t s = 0; s < nb; ++s)
        for (const auto& [body, m] : unconstrained[s])
          if (body == b) gc[s] << m.col(q).head<3>(), rot_[static_cast<std::size_t>(bodies[s])] * m.col(q).tail<3>();
      if (turns) {  // R(q) in A's angular part and in W
        const auto s = static_cast<std::size_t>(sb);
        const Eigen::Matrix3d& dr = d_rot[s][static_cast<std::size_t>(q - 3)];
        const Eigen::Matrix3d& r = rot_[static_cast<std::size_t>(b)];
        const Eigen::Matrix3d& ji = body_law(static_cast<std::size_t>(b)).inv_inertia;
        gc[s].tail<3>() += dr * applied_rate[s] + (dr * ji * r.transpose() + r * ji * dr.transpose()) * wrench[s].tail<3>();
      }
      // The rows on body b: dJ acc + dbias, and dJ^T lambda.
      if (sb >= 0)
        for (const int jq : joints_on[static_cast<std::size_t>(sb)]) {
          const ClusterJoint& cj = rc.joints()[static_cast<std::size_t>(jq)];
          const int col = (cj.a == sb ? 0 : body_states) + q;
          for (int r = cj.first_row; r < cj.first_row + cj.rows; ++r) {
            const auto d = d_row[static_cast<std::size_t>(r)].col(col);
            double zr = d[12];
            if (cj.a >= 0) {
              zr += d.head<6>().dot(acc[static_cast<std::size_t>(cj.a)]);
              nu[static_cast<std::size_t>(cj.a)] += lambda[r] * d.head<6>();
            }
            if (cj.b >= 0) {
              zr += d.segment<6>(6).dot(acc[static_cast<std::size_t>(cj.b)]);
              nu[static_cast<std::size_t>(cj.b)] += lambda[r] * d.segment<6>(6);
            }
            zc[r] = zr;
          }
        }
      for (std::size_t s = 0; s < nb; ++s) {
        gc[s].head<3>() += rc.inv_mass[s] * nu[s].head<3>();
        gc[s].tail<3>() += rc.inv_inertia[s] * nu[s].tail<3>();
      }
      // + J g; after the solve z = -dlambda, and dacc = g - W J^T z.
      for (const ClusterJoint& cj : rc.joints())
        for (int r = cj.first_row; r < cj.first_row + cj.rows; ++r) {
          const RowJacobian& j = rc.rows[static_cast<std::size_t>(r)].j;
          if (cj.a >= 0) zc[r] += j.head<6>().dot(gc[static_cast<std::size_t>(cj.a)]);
          if (cj.b >= 0) zc[r] += j.tail<6>().dot(gc[static_cast<std::size_t>(cj.b)]);
        }
    }
    rc.solve(z);
    for (std::size_t c = 0; c < count; ++c) {
      const auto [b, q, sb, turns] = columns[first + c];
      const Vector6d* gc = g.data() + c * nb;
      rc.motion(z.col(static_cast<Eigen::Index>(c)), moved);
      for (std::size_t s = 0; s < nb; ++s) {
        const Vector6d dacc = gc[s] - moved[s];
        const Eigen::Matrix3d& r = rot_[static_cast<std::size_t>(bodies[s])];
        const auto at = static_cast<Eigen::Index>(6 * s);
        rates.segment<3>(at) = dacc.head<3>();
        rates.segment<3>(at + 3) = r.transpose() * dacc.tail<3>();  // w' = R^T (world angular acceleration)
        if (turns && static_cast<int>(s) == sb)
          rates.segment<3>(at + 3) += d_rot[s][static_cast<std::size_t>(q - 3)].transpose() * acc[s].tail<3>();
      }
      column(b, q, rates);
    }
  }
}

}  // namespace mbsflow
