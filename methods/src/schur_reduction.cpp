#include "schur_reduction.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <type_traits>

#include "mbsflow/error.hpp"
#include "scalar_archive.hpp"

namespace mbsflow {

namespace {

constexpr int largest_block = 16;

// Products without the NaN recovery of std::complex's operator* (which the compiler does
// not inline): these loops are most of a reduction's time, and a NaN in them shows as a
// failed Newton iteration anyway.
inline double times(double a, double b) { return a * b; }
inline std::complex<double> times(std::complex<double> a, std::complex<double> b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}
inline std::complex<double> times(double a, std::complex<double> b) { return {a * b.real(), a * b.imag()}; }

// The slot of (row, column) in a compressed pattern with sorted columns; the entry exists.
int slot_of(const std::vector<int>& outer, const std::vector<int>& inner, int row, int column) {
  const auto first = inner.begin() + outer[static_cast<std::size_t>(column)];
  const auto last = inner.begin() + outer[static_cast<std::size_t>(column) + 1];
  return static_cast<int>(std::lower_bound(first, last, row) - inner.begin());
}

void sort_unique(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

int index_in(std::span<const int> sorted, int value) {
  return static_cast<int>(std::lower_bound(sorted.begin(), sorted.end(), value) - sorted.begin());
}

// a (n x n, row-major) becomes its inverse: Gauss-Jordan with partial pivoting. False when
// a pivot is zero or not finite.
template <class Scalar>
bool invert_small(Scalar* a, int n) {
  Scalar aug[largest_block][2 * largest_block];
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < 2 * n; ++c) aug[r][c] = c < n ? a[r * n + c] : Scalar(c - n == r ? 1 : 0);
  for (int c = 0; c < n; ++c) {
    int pivot = c;
    for (int r = c + 1; r < n; ++r)
      if (std::abs(aug[r][c]) > std::abs(aug[pivot][c])) pivot = r;
    const double size = std::abs(aug[pivot][c]);
    if (!(size > 0) || !std::isfinite(size)) return false;
    if (pivot != c)
      for (int k = 0; k < 2 * n; ++k) std::swap(aug[pivot][k], aug[c][k]);
    const Scalar inv = Scalar(1) / aug[c][c];
    for (int k = 0; k < 2 * n; ++k) aug[c][k] = times(aug[c][k], inv);
    for (int r = 0; r < n; ++r) {
      if (r == c) continue;
      const Scalar f = aug[r][c];
      if (f == Scalar(0)) continue;
      for (int k = 0; k < 2 * n; ++k) aug[r][k] -= times(f, aug[c][k]);
    }
  }
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) a[r * n + c] = aug[r][n + c];
  return true;
}

}  // namespace

std::shared_ptr<const SchurPattern> make_schur_pattern(const Eigen::SparseMatrix<double>& j,
                                                       const std::vector<RowRange>& ranges) {
  const Eigen::Index n = j.rows();
  if (ranges.empty() || j.cols() != n || !j.isCompressed()) return nullptr;
  auto p = std::make_shared<SchurPattern>();
  const auto un = static_cast<std::size_t>(n);
  std::vector<int> block_of(un, -1), local(un, 0), reduced(un, -1);
  for (const RowRange& r : ranges) {
    if (r.begin < 0 || r.end > n || r.end - r.begin < 1 || r.end - r.begin > largest_block) return nullptr;
    for (Eigen::Index i = r.begin; i < r.end; ++i) {
      if (block_of[static_cast<std::size_t>(i)] >= 0) return nullptr;
      block_of[static_cast<std::size_t>(i)] = static_cast<int>(p->blocks.size());
      local[static_cast<std::size_t>(i)] = static_cast<int>(i - r.begin);
    }
    SchurPattern::Block b;
    b.begin = r.begin;
    b.size = static_cast<int>(r.end - r.begin);
    p->blocks.push_back(b);
  }
  for (Eigen::Index i = 0; i < n; ++i)
    if (block_of[static_cast<std::size_t>(i)] < 0) {
      reduced[static_cast<std::size_t>(i)] = static_cast<int>(p->kept.size());
      p->kept.push_back(static_cast<int>(i));
    }
  p->kept_count = static_cast<Eigen::Index>(p->kept.size());
  if (p->kept_count == 0) return nullptr;

  // J's entries by kind, with rows and columns as they are; those of the blocks grouped by
  // block (a count, then a fill, in column order).
  struct Raw {
    int k, row, col;
  };
  const std::size_t nb = p->blocks.size();
  const int* outer = j.outerIndexPtr();
  const int* inner = j.innerIndexPtr();
  enum Kind { in_block, to_kept, from_kept, kept_only };
  auto kind_of = [&](int row, Eigen::Index c) {
    const int bc = block_of[static_cast<std::size_t>(c)], br = block_of[static_cast<std::size_t>(row)];
    return bc >= 0 ? (br >= 0 ? in_block : to_kept) : (br >= 0 ? from_kept : kept_only);
  };
  // start[kind][b]: where block b's entries of that kind begin (block of the column for
  // in_block and to_kept, of the row for from_kept).
  std::vector<int> start[3];
  for (auto& v : start) v.assign(nb + 1, 0);
  std::size_t dd_count = 0;
  for (Eigen::Index c = 0; c < n; ++c)
    for (int k = outer[c]; k < outer[c + 1]; ++k) {
      const Kind kind = kind_of(inner[k], c);
      if (kind == in_block && block_of[static_cast<std::size_t>(inner[k])] != block_of[static_cast<std::size_t>(c)])
        return nullptr;  // a block's rate reads another block: not block diagonal
      if (kind == kept_only)
        ++dd_count;
      else
        ++start[kind][static_cast<std::size_t>(block_of[static_cast<std::size_t>(kind == from_kept ? inner[k] : c)]) + 1];
    }
  std::vector<Raw> raw[3];
  for (int kind = 0; kind < 3; ++kind) {
    for (std::size_t b = 0; b < nb; ++b) start[kind][b + 1] += start[kind][b];
    raw[kind].resize(static_cast<std::size_t>(start[kind][nb]));
  }
  std::vector<Raw> dd;
  dd.reserve(dd_count);
  {
    std::vector<int> next[3] = {start[0], start[1], start[2]};
    for (Eigen::Index c = 0; c < n; ++c) {
      const auto uc = static_cast<std::size_t>(c);
      for (int k = outer[c]; k < outer[c + 1]; ++k) {
        const auto r = static_cast<std::size_t>(inner[k]);
        switch (kind_of(inner[k], c)) {
          case in_block: raw[in_block][static_cast<std::size_t>(next[in_block][static_cast<std::size_t>(block_of[uc])]++)] = {k, local[r], local[uc]}; break;
          case to_kept: raw[to_kept][static_cast<std::size_t>(next[to_kept][static_cast<std::size_t>(block_of[uc])]++)] = {k, reduced[r], local[uc]}; break;
          case from_kept: raw[from_kept][static_cast<std::size_t>(next[from_kept][static_cast<std::size_t>(block_of[r])]++)] = {k, local[r], reduced[uc]}; break;
          default: dd.push_back({k, reduced[r], reduced[uc]}); break;
        }
      }
    }
  }
  auto segment = [&](int kind, std::size_t b) {
    return std::span<const Raw>(raw[kind].data() + start[kind][b], raw[kind].data() + start[kind][b + 1]);
  };

  // Per block, the columns of S its J_ED rows reach and the rows its J_DE columns reach:
  // one field of its entries, sorted and unique, appended to `to` between begin and end.
  std::vector<int> unique;
  auto gather = [&](std::span<const Raw> entries, int Raw::*field, std::vector<int>& to, int& begin, int& end) {
    unique.clear();
    for (const Raw& e : entries) unique.push_back(e.*field);
    sort_unique(unique);
    begin = static_cast<int>(to.size());
    to.insert(to.end(), unique.begin(), unique.end());
    end = static_cast<int>(to.size());
  };
  for (std::size_t b = 0; b < nb; ++b) {
    SchurPattern::Block& blk = p->blocks[b];
    gather(segment(from_kept, b), &Raw::col, p->columns, blk.columns_begin, blk.columns_end);
    gather(segment(to_kept, b), &Raw::row, p->rows, blk.rows_begin, blk.rows_end);
  }

  // S's pattern: J_DD, the diagonal, and every block's rows x columns; per column the
  // candidates counted, filled, then sorted and made unique in place.
  const auto nk = static_cast<std::size_t>(p->kept_count);
  std::vector<int> candidates_at(nk + 1, 0);
  for (const Raw& e : dd) ++candidates_at[static_cast<std::size_t>(e.col) + 1];
  for (std::size_t c = 0; c < nk; ++c) ++candidates_at[c + 1];
  for (const SchurPattern::Block& blk : p->blocks)
    for (int i = blk.columns_begin; i < blk.columns_end; ++i)
      candidates_at[static_cast<std::size_t>(p->columns[static_cast<std::size_t>(i)]) + 1] += blk.height();
  for (std::size_t c = 0; c < nk; ++c) candidates_at[c + 1] += candidates_at[c];
  std::vector<int> candidates(static_cast<std::size_t>(candidates_at[nk]));
  {
    std::vector<int> next(candidates_at.begin(), candidates_at.end() - 1);
    auto put = [&](int column, int row) { candidates[static_cast<std::size_t>(next[static_cast<std::size_t>(column)]++)] = row; };
    for (const Raw& e : dd) put(e.col, e.row);
    for (std::size_t c = 0; c < nk; ++c) put(static_cast<int>(c), static_cast<int>(c));
    for (const SchurPattern::Block& blk : p->blocks)
      for (int i = blk.columns_begin; i < blk.columns_end; ++i)
        for (int r = blk.rows_begin; r < blk.rows_end; ++r) put(p->columns[static_cast<std::size_t>(i)], p->rows[static_cast<std::size_t>(r)]);
  }
  p->s_outer.assign(nk + 1, 0);
  p->s_inner.reserve(candidates.size());
  for (std::size_t c = 0; c < nk; ++c) {
    const auto first = candidates.begin() + candidates_at[c], last = candidates.begin() + candidates_at[c + 1];
    std::sort(first, last);
    p->s_inner.insert(p->s_inner.end(), first, std::unique(first, last));
    p->s_outer[c + 1] = static_cast<int>(p->s_inner.size());
  }

  for (const Raw& e : dd) p->dd.push_back({e.k, slot_of(p->s_outer, p->s_inner, e.row, e.col)});
  p->diagonal.resize(nk);
  for (std::size_t r = 0; r < nk; ++r)
    p->diagonal[r] = slot_of(p->s_outer, p->s_inner, static_cast<int>(r), static_cast<int>(r));
  for (std::size_t b = 0; b < nb; ++b) {
    SchurPattern::Block& blk = p->blocks[b];
    const std::span<const int> cols(p->columns.data() + blk.columns_begin, p->columns.data() + blk.columns_end);
    const std::span<const int> rows(p->rows.data() + blk.rows_begin, p->rows.data() + blk.rows_end);
    const int width = blk.width();
    blk.ee_begin = static_cast<int>(p->ee.size());
    for (const Raw& e : segment(in_block, b)) p->ee.push_back({e.k, e.row * blk.size + e.col});
    blk.ee_end = static_cast<int>(p->ee.size());
    blk.ed_begin = static_cast<int>(p->ed.size());
    for (const Raw& e : segment(from_kept, b)) p->ed.push_back({e.k, e.row * width + index_in(cols, e.col)});
    blk.ed_end = static_cast<int>(p->ed.size());
    blk.minv_begin = p->minv_size;
    p->minv_size += blk.size * blk.size;
    blk.w_begin = p->w_size;
    p->w_size += blk.size * width;
    blk.v_begin = p->v_size;
    p->v_size += blk.size * blk.height();
    blk.de_begin = static_cast<int>(p->de.size());
    for (const Raw& e : segment(to_kept, b)) p->de.push_back({e.k, blk.v_begin + index_in(rows, e.row) * blk.size + e.col});
    blk.de_end = static_cast<int>(p->de.size());
    blk.slots_begin = static_cast<int>(p->slots.size());
    for (int r : rows)
      for (int c : cols) p->slots.push_back(slot_of(p->s_outer, p->s_inner, r, c));
    blk.z_begin = p->eliminated;
    p->eliminated += blk.size;
  }
  return p;
}

bool same_pattern(const std::vector<int>& outer, const std::vector<int>& inner, const Eigen::SparseMatrix<double>& j) {
  const int* o = j.outerIndexPtr();
  const int* i = j.innerIndexPtr();
  return j.isCompressed() && !outer.empty() && std::equal(outer.begin(), outer.end(), o, o + j.outerSize() + 1) &&
         std::equal(inner.begin(), inner.end(), i, i + j.nonZeros());
}

std::shared_ptr<const SchurPattern> Elimination::pattern_for(const Eigen::SparseMatrix<double>& j) {
  std::lock_guard lock(mutex_);
  if (!same_pattern(outer_, inner_, j)) {
    pattern_ = make_schur_pattern(j, blocks_);
    outer_.assign(j.outerIndexPtr(), j.outerIndexPtr() + j.outerSize() + 1);
    inner_.assign(j.innerIndexPtr(), j.innerIndexPtr() + j.nonZeros());
  }
  return pattern_;
}

namespace {

// The per-block loops with the block size known at compile time where it is a common one
// (3: a position, 4: a quaternion), else at run time (M = 0).
template <int M>
int size_of(const SchurPattern::Block& b) {
  return M > 0 ? M : b.size;
}

// W = M^-1 J_ED, and S -= gamma^2 J_DE W over the block's rows x columns.
template <int M, class Scalar>
void block_product(const SchurPattern& p, const SchurPattern::Block& b, const Scalar* minv, const double* ed,
                   const double* v, Scalar g2, Scalar* w, Scalar* s) {
  const int m = size_of<M>(b), width = b.width(), height = b.height();
  for (int i = 0; i < m; ++i)
    for (int c = 0; c < width; ++c) {
      Scalar acc(0);
      if (b.identity())
        acc = ed[i * width + c];
      else
        for (int l = 0; l < m; ++l) acc += times(minv[i * m + l], Scalar(ed[l * width + c]));
      w[i * width + c] = acc;
    }
  const int* slot = p.slots.data() + b.slots_begin;
  for (int i = 0; i < height; ++i)
    for (int c = 0; c < width; ++c) {
      Scalar acc(0);
      for (int l = 0; l < m; ++l) acc += times(v[i * m + l], w[l * width + c]);
      s[slot[i * width + c]] -= times(g2, acc);
    }
}

// z = M^-1 b_E, x_D += gamma J_DE z over the block's rows.
template <int M, class Scalar, class Vector>
void block_rhs(const SchurPattern& p, const SchurPattern::Block& b, const Scalar* minv, const double* v, Scalar gamma,
               const Vector& rhs, Scalar* z, Vector& x_d) {
  const int m = size_of<M>(b);
  Scalar zg[largest_block];
  for (int i = 0; i < m; ++i) {
    Scalar acc(0);
    if (b.identity())
      acc = rhs[b.begin + i];
    else
      for (int c = 0; c < m; ++c) acc += times(minv[i * m + c], rhs[b.begin + c]);
    z[i] = acc;
    zg[i] = times(gamma, acc);
  }
  const int* row = p.rows.data() + b.rows_begin;
  for (int i = 0; i < b.height(); ++i) {
    Scalar acc(0);
    for (int l = 0; l < m; ++l) acc += times(v[i * m + l], zg[l]);
    x_d[row[i]] += acc;
  }
}

template <class F>
void by_size(const SchurPattern::Block& b, F&& f) {
  switch (b.size) {
    case 3: f(std::integral_constant<int, 3>()); break;
    case 4: f(std::integral_constant<int, 4>()); break;
    default: f(std::integral_constant<int, 0>()); break;
  }
}

}  // namespace

template <class Scalar>
void SchurReduction<Scalar>::reduce(const SchurPattern& p, const Eigen::SparseMatrix<double>& j, Scalar gamma,
                                    Scalar* s) {
  p_ = &p;
  gamma_ = gamma;
  const double* jv = j.valuePtr();
  minv_.resize(static_cast<std::size_t>(p.minv_size));
  w_.resize(static_cast<std::size_t>(p.w_size));
  v_.assign(static_cast<std::size_t>(p.v_size), 0.0);
  for (const SchurPattern::Entry& e : p.de) v_[static_cast<std::size_t>(e.at)] = jv[e.k];
  std::fill(s, s + p.s_outer.back(), Scalar(0));
  for (int d : p.diagonal) s[d] = Scalar(1);
  for (const SchurPattern::Entry& e : p.dd) s[e.at] -= times(gamma, Scalar(jv[e.k]));
  const Scalar g2 = times(gamma, gamma);
  for (const SchurPattern::Block& b : p.blocks) {
    const int m = b.size;
    Scalar* minv = minv_.data() + b.minv_begin;
    std::fill(minv, minv + m * m, Scalar(0));
    for (int i = 0; i < m; ++i) minv[i * m + i] = Scalar(1);
    if (!b.identity()) {
      for (int e = b.ee_begin; e < b.ee_end; ++e) {
        const SchurPattern::Entry& x = p.ee[static_cast<std::size_t>(e)];
        minv[x.at] -= times(gamma, Scalar(jv[x.k]));
      }
      if (!invert_small(minv, m)) throw RunError("Newton matrix is singular (in an eliminated block)");
    }
    ed_.assign(static_cast<std::size_t>(m * b.width()), 0.0);
    for (int e = b.ed_begin; e < b.ed_end; ++e) {
      const SchurPattern::Entry& x = p.ed[static_cast<std::size_t>(e)];
      ed_[static_cast<std::size_t>(x.at)] += jv[x.k];
    }
    by_size(b, [&](auto size) {
      block_product<decltype(size)::value>(p, b, minv, ed_.data(), v_.data() + b.v_begin, g2, w_.data() + b.w_begin, s);
    });
  }
}

template <class Scalar>
void SchurReduction<Scalar>::reduce_rhs(const Vector& b) const {
  const SchurPattern& p = *p_;
  x_d_.resize(p.kept_count);
  z_e_.resize(p.eliminated);
  for (Eigen::Index r = 0; r < p.kept_count; ++r) x_d_[r] = b[p.kept[static_cast<std::size_t>(r)]];
  for (const SchurPattern::Block& blk : p.blocks)
    by_size(blk, [&](auto size) {
      block_rhs<decltype(size)::value>(p, blk, minv_.data() + blk.minv_begin, v_.data() + blk.v_begin, gamma_, b,
                                       z_e_.data() + blk.z_begin, x_d_);
    });
}

template <class Scalar>
void SchurReduction<Scalar>::expand(Vector& b) const {
  const SchurPattern& p = *p_;
  for (Eigen::Index r = 0; r < p.kept_count; ++r) b[p.kept[static_cast<std::size_t>(r)]] = x_d_[r];
  for (const SchurPattern::Block& blk : p.blocks) {
    const Scalar* w = w_.data() + blk.w_begin;
    const Scalar* z = z_e_.data() + blk.z_begin;
    const int* column = p.columns.data() + blk.columns_begin;
    const int width = blk.width();
    for (int i = 0; i < blk.size; ++i) {
      Scalar acc(0);
      for (int c = 0; c < width; ++c) acc += times(w[i * width + c], x_d_[column[c]]);
      b[blk.begin + i] = z[i] + times(gamma_, acc);
    }
  }
}

template <class Scalar>
void SchurReduction<Scalar>::save(StateWriter& out) const {
  out.vector(as_reals(&gamma_, 1));
  out.vector(as_reals(minv_.data(), static_cast<Eigen::Index>(minv_.size())));
  out.vector(as_reals(w_.data(), static_cast<Eigen::Index>(w_.size())));
  out.vector(Eigen::Map<const Eigen::VectorXd>(v_.data(), static_cast<Eigen::Index>(v_.size())));
}

template <class Scalar>
void SchurReduction<Scalar>::restore(StateReader& in) {
  const std::vector<Scalar> gamma = from_reals<Scalar>(in.vector(), in);
  std::vector<Scalar> minv = from_reals<Scalar>(in.vector(), in), w = from_reals<Scalar>(in.vector(), in);
  const Eigen::VectorXd v = in.vector();
  if (gamma.size() != 1 || minv.size() != minv_.size() || w.size() != w_.size() ||
      static_cast<std::size_t>(v.size()) != v_.size())
    in.fail("a reduced Newton matrix does not fit the Jacobian's pattern");
  gamma_ = gamma[0];
  minv_ = std::move(minv);
  w_ = std::move(w);
  std::copy(v.data(), v.data() + v.size(), v_.begin());
}

template class SchurReduction<double>;
template class SchurReduction<std::complex<double>>;

}  // namespace mbsflow
