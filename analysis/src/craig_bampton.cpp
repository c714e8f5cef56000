#include "mbsflow/analysis/craig_bampton.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsShiftSolver.h>
#include <algorithm>
#include <numbers>
#include <unordered_map>
#include <unordered_set>

#include "blas_product.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Cholesky = Eigen::CholmodSupernodalLLT<Sparse, Eigen::Lower>;

// K_ii^-1 as Spectra's shift-invert operator: the shift is 0, the part held at its
// interface being positive definite.
class HeldInverse {
 public:
  using Scalar = double;
  HeldInverse(const Cholesky& factor, Eigen::Index n) : factor_(factor), n_(n) {}
  Eigen::Index rows() const { return n_; }
  Eigen::Index cols() const { return n_; }
  void set_shift(double sigma) {
    if (sigma != 0.0) throw Error("craig_bampton: the held part's inverse has no shift");
  }
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<Eigen::VectorXd>(y_out, n_) = factor_.solve(Eigen::Map<const Eigen::VectorXd>(x_in, n_));
  }

 private:
  const Cholesky& factor_;
  Eigen::Index n_;
};

constexpr double two_pi = 2.0 * std::numbers::pi;

}  // namespace

std::unordered_map<long, std::array<Eigen::Index, 6>> dof_rows_by_node(const std::vector<FeDof>& dofs) {
  std::unordered_map<long, std::array<Eigen::Index, 6>> rows;
  for (std::size_t k = 0; k < dofs.size(); ++k) {
    auto [at, added] = rows.try_emplace(dofs[k].node, std::array<Eigen::Index, 6>{-1, -1, -1, -1, -1, -1});
    at->second[static_cast<std::size_t>(dofs[k].direction - 1)] = static_cast<Eigen::Index>(k);
  }
  return rows;
}

Eigen::MatrixXd rigid_body_fields(const std::vector<FeDof>& dofs, const std::vector<Eigen::Vector3d>& dof_position,
                                  const Eigen::Vector3d& centre) {
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(dofs.size()), 6);
  for (std::size_t k = 0; k < dofs.size(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    const int d = dofs[k].direction - 1;
    if (d < 3) {
      r(row, d) = 1.0;
      const Eigen::Vector3d arm = dof_position[k] - centre;
      for (int axis = 0; axis < 3; ++axis) r(row, 3 + axis) = Eigen::Vector3d::Unit(axis).cross(arm)[d];
    } else {
      r(row, d) = 1.0;  // a rotation DOF turns with the rigid rotation about its own axis
    }
  }
  return r;
}

MassProperties mass_properties(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position) {
  MassProperties p;
  const Eigen::MatrixXd about_origin = rigid_body_fields(fe.dofs, dof_position, Eigen::Vector3d::Zero());
  const Eigen::MatrixXd gram = about_origin.transpose() * (fe.mass * about_origin);
  p.mass = gram(0, 0);
  if (!(p.mass > 0.0)) throw InputError("the mass matrix gives the part no mass (" + std::to_string(p.mass) + " kg)");
  // translation along j against rotation about k: s . (e_j x e_k), s the first moment of mass
  const Eigen::Vector3d first_moment(gram(1, 5), gram(2, 3), gram(0, 4));
  p.centre = first_moment / p.mass;
  const Eigen::MatrixXd rotations = rigid_body_fields(fe.dofs, dof_position, p.centre).rightCols<3>();
  p.inertia = rotations.transpose() * (fe.mass * rotations);  // int rho (e_k x r).(e_l x r) dV
  return p;
}

ReducedPart craig_bampton(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position,
                          const CraigBamptonOptions& o) {
  const auto n = static_cast<Eigen::Index>(fe.dofs.size());
  if (fe.stiffness.rows() != n || fe.stiffness.cols() != n || fe.mass.rows() != n || fe.mass.cols() != n)
    throw InputError("the stiffness and mass matrices must both be " + std::to_string(n) + " x " + std::to_string(n) +
                     " (one row per DOF)");
  if (static_cast<Eigen::Index>(dof_position.size()) != n) throw Error("craig_bampton: a position per DOF");
  // The interface DOFs first (in the order of the nodes given, each node's by direction),
  // then the others in the model's order.
  std::unordered_map<long, std::vector<Eigen::Index>> by_node;
  for (Eigen::Index k = 0; k < n; ++k) by_node[fe.dofs[static_cast<std::size_t>(k)].node].push_back(k);
  std::vector<Eigen::Index> order;
  std::vector<char> boundary(static_cast<std::size_t>(n), 0);
  for (long node : o.interface_nodes) {
    const auto at = by_node.find(node);
    if (at == by_node.end()) throw InputError("interface node " + std::to_string(node) + ": no DOF of the FE model is on it");
    for (Eigen::Index k : at->second) {
      if (boundary[static_cast<std::size_t>(k)]) throw InputError("interface node " + std::to_string(node) + " is named twice");
      boundary[static_cast<std::size_t>(k)] = 1;
      order.push_back(k);
    }
  }
  const auto nb = static_cast<Eigen::Index>(order.size()), ni = n - nb;
  if (nb == 0) throw InputError("give the interface nodes (--interface): the DOFs the reduced part keeps");
  for (Eigen::Index k = 0; k < n; ++k)
    if (!boundary[static_cast<std::size_t>(k)]) order.push_back(k);
  if (o.modes < 0 || o.modes > ni)
    throw InputError("--modes " + std::to_string(o.modes) + ": the part has " + std::to_string(ni) +
                     " DOFs besides its interface; ask for fewer fixed-interface modes");
  // The interface must fix every rigid motion, else K_ii is singular (and a Cholesky of it
  // may only find so at rounding's level): the rigid fields on the interface DOFs have
  // rank 6.
  // (about the interface's centroid, each field scaled to unit length: the test does not
  // depend on where the part lies or on its units).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < nb; ++k) centroid += dof_position[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])];
  centroid /= static_cast<double>(nb);
  const Eigen::MatrixXd rigid_all = rigid_body_fields(fe.dofs, dof_position, centroid);
  Eigen::MatrixXd rigid_b(nb, 6);
  for (Eigen::Index k = 0; k < nb; ++k) rigid_b.row(k) = rigid_all.row(order[static_cast<std::size_t>(k)]);
  for (Eigen::Index c = 0; c < 6; ++c)
    if (rigid_b.col(c).norm() > 0) rigid_b.col(c).normalize();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(rigid_b).singularValues();
  if (nb < 6 || !(sv[5] > 1e-6 * sv[0]))
    throw InputError("the interface does not hold the part: its nodes leave a rigid motion free (for a solid give at least "
                     "three nodes not on a line, or nodes with rotation DOFs)");
  // P maps a model DOF to its place in `order`.
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p(n);
  for (Eigen::Index k = 0; k < n; ++k) p.indices()[order[static_cast<std::size_t>(k)]] = static_cast<int>(k);
  Sparse k_p, m_p;
  k_p = fe.stiffness.twistedBy(p);
  m_p = fe.mass.twistedBy(p);
  const Sparse k_ii = k_p.bottomRightCorner(ni, ni), m_ii = m_p.bottomRightCorner(ni, ni);
  const Eigen::MatrixXd k_ib = Eigen::MatrixXd(k_p.bottomLeftCorner(ni, nb));

  const auto phase = [&](const char* what) {
    if (o.phase) o.phase(what);
  };
  phase("factorise the interior stiffness (CHOLMOD)");
  Cholesky factor;
  factor.compute(k_ii);
  if (factor.info() != Eigen::Success)
    throw InputError("the interface does not hold the part (its stiffness without the interface DOFs is singular): give "
                     "interface nodes that fix every rigid motion (for a solid, at least three not on a line)");

  ReducedPart r;
  r.modes = o.modes;
  const Eigen::Index nr = nb + o.modes;
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(n, nr);  // in `order`'s rows
  t.topLeftCorner(nb, nb).setIdentity();
  phase("constraint modes");
  t.bottomLeftCorner(ni, nb) = -factor.solve(k_ib);
  phase("fixed-interface modes");
  if (o.modes > 0) {
    Eigen::VectorXd lambda;
    Eigen::MatrixXd phi;
    if (2 * o.modes + 1 > ni) {
      // Nearly every interior mode: Lanczos would span the whole space; dense is exact there.
      const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(k_ii), Eigen::MatrixXd(m_ii)};
      if (eig.info() != Eigen::Success) throw RunError("the fixed-interface modes did not converge (dense)");
      lambda = eig.eigenvalues().head(o.modes);
      phi = eig.eigenvectors().leftCols(o.modes);
    } else {
      HeldInverse op(factor, ni);
      Spectra::SparseSymMatProd<double> b(m_ii);
      const Eigen::Index ncv = std::min<Eigen::Index>(ni, std::max<Eigen::Index>(2 * o.modes + 1, o.modes + 20));
      Spectra::SymGEigsShiftSolver<HeldInverse, Spectra::SparseSymMatProd<double>, Spectra::GEigsMode::ShiftInvert> eigs(
          op, b, o.modes, ncv, 0.0);
      eigs.init();
      eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-12);
      if (eigs.info() != Spectra::CompInfo::Successful)
        throw RunError("the fixed-interface modes did not converge (Spectra, shift-invert Lanczos): ask for fewer --modes");
      lambda = eigs.eigenvalues();
      phi = eigs.eigenvectors();
    }
    std::vector<Eigen::Index> rank(static_cast<std::size_t>(o.modes));
    for (Eigen::Index j = 0; j < o.modes; ++j) rank[static_cast<std::size_t>(j)] = j;
    std::sort(rank.begin(), rank.end(), [&](Eigen::Index a, Eigen::Index b2) { return lambda[a] < lambda[b2]; });
    r.fixed_frequency.resize(o.modes);
    for (Eigen::Index j = 0; j < o.modes; ++j) {
      const Eigen::Index from = rank[static_cast<std::size_t>(j)];
      Eigen::VectorXd v = phi.col(from);
      v /= std::sqrt(v.dot(m_ii * v));  // mass-normalised
      t.col(nb + j).tail(ni) = v;
      r.fixed_frequency[j] = std::sqrt(std::max(lambda[from], 0.0)) / two_pi;
    }
  }
  phase("reduced matrices");
  // Block by block, never T^T K T whole: K_r = [K_bb + K_bi Psi, 0; 0, Phi^T K_ii Phi] (the
  // coupling Phi^T (K_ib + K_ii Psi) is zero: K_ii Psi = -K_ib), and
  // M_r = [M_bb + M_bi Psi + Psi^T M_ib + Psi^T M_ii Psi, M_bi Phi + Psi^T M_ii Phi; ., Phi^T M_ii Phi].
  const Sparse k_bi = k_p.topRightCorner(nb, ni), m_bi = m_p.topRightCorner(nb, ni);
  const Eigen::MatrixXd k_bb = Eigen::MatrixXd(k_p.topLeftCorner(nb, nb)), m_bb = Eigen::MatrixXd(m_p.topLeftCorner(nb, nb));
  const auto psi = t.bottomLeftCorner(ni, nb);
  const auto phi = t.bottomRightCorner(ni, o.modes);
  r.stiffness = Eigen::MatrixXd::Zero(nr, nr);
  r.mass = Eigen::MatrixXd::Zero(nr, nr);
  r.stiffness.topLeftCorner(nb, nb) = k_bb + k_bi * psi;
  const Eigen::MatrixXd m_bi_psi = m_bi * psi;
  r.mass.topLeftCorner(nb, nb) = m_bb + m_bi_psi + m_bi_psi.transpose() + transposed_product(psi, Eigen::MatrixXd(m_ii * psi));
  if (o.modes > 0) {
    const Eigen::MatrixXd m_phi = m_ii * phi;
    r.stiffness.bottomRightCorner(o.modes, o.modes) = phi.transpose() * (k_ii * phi);
    r.mass.bottomRightCorner(o.modes, o.modes) = phi.transpose() * m_phi;
    r.mass.topRightCorner(nb, o.modes) = m_bi * phi + transposed_product(psi, m_phi);
    r.mass.bottomLeftCorner(o.modes, nb) = r.mass.topRightCorner(nb, o.modes).transpose();
  }
  r.stiffness = 0.5 * (r.stiffness + r.stiffness.transpose()).eval();  // symmetric to rounding
  r.mass = 0.5 * (r.mass + r.mass.transpose()).eval();
  for (Eigen::Index k = 0; k < nb; ++k) r.interface_dofs.push_back(fe.dofs[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])]);
  phase("mass properties and couplings");
  r.shapes.resize(n, nr);
  for (Eigen::Index k = 0; k < n; ++k) r.shapes.row(order[static_cast<std::size_t>(k)]) = t.row(k);
  t.resize(0, 0);
  r.properties = mass_properties(fe, dof_position);
  const Eigen::MatrixXd rigid = rigid_body_fields(fe.dofs, dof_position, r.properties.centre);
  const Eigen::MatrixXd mass_rigid = fe.mass * rigid;
  r.rigid_coupling = transposed_product(mass_rigid, r.shapes);
  phase("floating frame: elastic modes and inertia invariants");
  r.floating = floating_frame(fe, dof_position, r);
  return r;
}

TiedModel tie_rigidly(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position, const std::vector<long>& face_nodes,
                      long master, const Eigen::Vector3d& centre) {
  const std::unordered_set<long> face(face_nodes.begin(), face_nodes.end());
  const auto n = static_cast<Eigen::Index>(fe.dofs.size());
  const Eigen::MatrixXd rigid = rigid_body_fields(fe.dofs, dof_position, centre);
  TiedModel out;
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<Eigen::Index> on_face;
  for (Eigen::Index k = 0; k < n; ++k) {
    const FeDof& d = fe.dofs[static_cast<std::size_t>(k)];
    if (d.node == master) throw InputError("node " + std::to_string(master) + " is in the model already: give the master another number");
    if (face.count(d.node)) {
      on_face.push_back(k);
      continue;
    }
    entries.emplace_back(k, static_cast<Eigen::Index>(out.fe.dofs.size()), 1.0);
    out.fe.dofs.push_back(d);
    out.dof_position.push_back(dof_position[static_cast<std::size_t>(k)]);
  }
  if (on_face.empty()) throw InputError("the face tied to node " + std::to_string(master) + " has no DOF in the model");
  const auto first_master = static_cast<Eigen::Index>(out.fe.dofs.size());
  for (int e = 0; e < 6; ++e) {
    out.fe.dofs.push_back({master, e + 1});
    out.dof_position.push_back(centre);
  }
  // A face DOF moves with the master as a rigid body does: u_p = u_m + theta_m x (p - centre).
  for (Eigen::Index k : on_face)
    for (int e = 0; e < 6; ++e)
      if (rigid(k, e) != 0.0) entries.emplace_back(k, first_master + e, rigid(k, e));
  out.tie.resize(n, first_master + 6);
  out.tie.setFromTriplets(entries.begin(), entries.end());
  const Sparse tie_t = out.tie.transpose();
  out.fe.stiffness = tie_t * fe.stiffness * out.tie;
  out.fe.mass = tie_t * fe.mass * out.tie;
  return out;
}

Eigen::VectorXd reduced_frequencies(const ReducedPart& part, bool held) {
  if (held) return part.fixed_frequency;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(part.stiffness, part.mass, Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) throw RunError("the reduced part's eigenvalues did not converge");
  Eigen::VectorXd f = eig.eigenvalues();
  for (Eigen::Index k = 0; k < f.size(); ++k) f[k] = std::sqrt(std::max(f[k], 0.0)) / two_pi;
  return f;
}

}  // namespace mbsflow
