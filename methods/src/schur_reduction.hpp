#pragma once
// (I - gamma J) x = b with some unknowns eliminated first. Split the unknowns into E, a
// union of small blocks whose rows of J reach other unknowns of E only inside their own
// block, and the rest D:
//
//   [ I - gamma J_EE    -gamma J_ED  ] [x_E]   [b_E]
//   [  -gamma J_DE    I - gamma J_DD ] [x_D] = [b_D]
//
// I - gamma J_EE is block diagonal, so with M = I - gamma J_EE and W = M^-1 J_ED
//
//   S x_D = b_D + gamma J_DE M^-1 b_E,  S = I - gamma J_DD - gamma^2 J_DE W
//   x_E = M^-1 b_E + gamma W x_D
//
// and only S needs a sparse LU. A multibody model's positions and quaternions are such
// blocks (r' = v, q' = q (x) (0, w) / 2 read only the same body's state): S keeps the 6
// velocity unknowns of every 13, with the body-pair pattern of the forces, so its
// factorisations and solves cost a fraction of the full matrix's. Per block, the rows of
// J_DE and the columns of J_ED it reaches are few (a body's neighbours), so both are kept
// as small dense matrices.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <complex>
#include <memory>
#include <mutex>
#include <vector>

#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/state_archive.hpp"

namespace mbsflow {

// The symbolic part, from J's pattern and the blocks: where every entry of J goes, and the
// pattern of S. The same for every shift, real or complex.
struct SchurPattern {
  struct Entry {  // entry k of J's values and where it goes in a block's dense matrix
    int k, at;
  };
  struct Block {
    Eigen::Index begin = 0;
    int size = 0;
    int ee_begin = 0, ee_end = 0;            // J_EE entries: at = row * size + column
    int ed_begin = 0, ed_end = 0;            // J_ED entries: at = row * width + index in columns
    int de_begin = 0, de_end = 0;            // J_DE entries: at = index in rows * size + column
    int columns_begin = 0, columns_end = 0;  // the unknowns of S its J_ED entries reach
    int rows_begin = 0, rows_end = 0;        // the unknowns of S its J_DE entries reach
    int slots_begin = 0;                     // S's slot of (rows[i], columns[c]) at i * width + c
    int minv_begin = 0, w_begin = 0, v_begin = 0, z_begin = 0;  // offsets of its numbers
    int width() const { return columns_end - columns_begin; }
    int height() const { return rows_end - rows_begin; }
    bool identity() const { return ee_begin == ee_end; }  // M = I
  };
  Eigen::Index kept_count = 0;
  std::vector<int> kept;  // unknown of S -> unknown of the full system
  std::vector<Block> blocks;
  std::vector<Entry> ee, ed, de, dd;  // dd: at = S's slot
  std::vector<int> columns, rows, slots, diagonal;  // diagonal: S's slot of (r, r)
  std::vector<int> s_outer, s_inner;                // S, compressed by column
  int minv_size = 0, w_size = 0, v_size = 0, eliminated = 0;
};

// The pattern for J and the blocks, or nullptr when the blocks do not qualify (overlap,
// outside the matrix, larger than 16, or a row of one block reaching into another block).
// J: compressed, rows sorted in every column.
std::shared_ptr<const SchurPattern> make_schur_pattern(const Eigen::SparseMatrix<double>& j,
                                                       const std::vector<RowRange>& blocks);

// Whether j, compressed, has the pattern outer / inner (a kept copy; empty: none kept).
bool same_pattern(const std::vector<int>& outer, const std::vector<int>& inner, const Eigen::SparseMatrix<double>& j);

// The blocks to eliminate and the pattern made for them, shared by the solvers of one
// integrator (its real and complex systems factorise shifts of the same J): the pattern
// is made once per pattern of J.
class Elimination {
 public:
  explicit Elimination(std::vector<RowRange> blocks) : blocks_(std::move(blocks)) {}
  std::shared_ptr<const SchurPattern> pattern_for(const Eigen::SparseMatrix<double>& j);

 private:
  std::vector<RowRange> blocks_;
  std::mutex mutex_;
  std::vector<int> outer_, inner_;
  std::shared_ptr<const SchurPattern> pattern_;
};

// The numbers for one J and gamma: S's values (written into s, laid out by the pattern),
// and what the solve needs.
template <class Scalar>
class SchurReduction {
 public:
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  // Throws RunError when a block of I - gamma J_EE is singular.
  void reduce(const SchurPattern& p, const Eigen::SparseMatrix<double>& j, Scalar gamma, Scalar* s_values);
  // x = (I - gamma J)^-1 b in place, with solve_s(x_D) solving S x_D = r in place.
  template <class SolveS>
  void solve(Vector& b, const SolveS& solve_s) const {
    std::lock_guard lock(scratch_mutex_);
    reduce_rhs(b);
    solve_s(x_d_);
    expand(b);
  }
  // Checkpoints: the numbers as they are (restore() needs reduce() with the same pattern
  // first, for the layout).
  void save(StateWriter& out) const;
  void restore(StateReader& in);

 private:
  void reduce_rhs(const Vector& b) const;  // z_E = M^-1 b_E, x_d_ = b_D + gamma J_DE z_E
  void expand(Vector& b) const;            // x_E = z_E + gamma W x_D, both into b
  const SchurPattern* p_ = nullptr;
  Scalar gamma_ = Scalar(0);
  // Per block, row-major: M^-1 (size x size), W (size x width), J_DE (height x size).
  std::vector<Scalar> minv_, w_;
  std::vector<double> v_, ed_;  // ed_: scratch of reduce()
  mutable std::mutex scratch_mutex_;
  mutable Vector x_d_, z_e_;
};

extern template class SchurReduction<double>;
extern template class SchurReduction<std::complex<double>>;

}  // namespace mbsflow
