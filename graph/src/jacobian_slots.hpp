#pragma once
// Where MultibodySystem::jacobian's writes land in the matrix's values: found by search on
// the first call, kept, and replayed in order by later calls (SlotWriter), or from a
// body's first write on by one thread (SlotCursor), every place checked against its rows.
#include <Eigen/SparseCore>
#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace mbsflow::jacobian_slots {

// The offset in jac's values of rows row..row+count-1 of column col, which the pattern
// must hold (then they are consecutive in the column: its rows are sorted).
inline int entries(const Eigen::SparseMatrix<double>& jac, Eigen::Index row, Eigen::Index col, int count = 1) {
  const int* first = jac.innerIndexPtr() + jac.outerIndexPtr()[col];
  const int* last = jac.innerIndexPtr() + jac.outerIndexPtr()[col + 1];
  const int* at = std::lower_bound(first, last, static_cast<int>(row));
  if (last - at < count || at[count - 1] != row + count - 1)
    throw std::logic_error("multibody Jacobian: entry outside the Jacobian pattern");
  return static_cast<int>(at - jac.innerIndexPtr());
}

// jacobian()'s writes into the matrix's values. The first call finds each one's place by
// search and keeps it; later calls with a matrix of the same column starts take the kept
// places in order, each checked against its rows, so a matrix of another pattern is still
// filled right: from the first place that does not fit, by search, and the places are
// found afresh at the next call.
class SlotWriter {
 public:
  SlotWriter(Eigen::SparseMatrix<double>& jac, std::vector<int>& outer, std::vector<int>& slots) : jac_(jac), slots_(slots) {
    const auto columns = static_cast<std::size_t>(jac.outerSize()) + 1;
    replay_ = jac.isCompressed() && !slots.empty() && outer.size() == columns &&
              std::equal(outer.begin(), outer.end(), jac.outerIndexPtr());
    if (!replay_) {
      slots.clear();
      outer.assign(jac.outerIndexPtr(), jac.outerIndexPtr() + columns);
    }
  }
  ~SlotWriter() {
    if (broken_ || !jac_.isCompressed() || (replay_ && next_ != slots_.size())) slots_.clear();
  }
  // Whether the places kept are being taken in order (not found by search).
  bool replaying() const { return replay_; }
  // How many writes are behind: the next write's index among the places kept.
  std::size_t position() const { return replay_ ? next_ : slots_.size(); }
  // The writes up to `position` made elsewhere (by SlotCursors, over the same places).
  void skip_to(std::size_t position) { next_ = position; }
  // From the start again, every place found by search and kept afresh.
  void restart() {
    slots_.clear();
    replay_ = broken_ = false;
    next_ = 0;
  }
  // The values at rows row..row+count-1 of column col.
  double* at(Eigen::Index row, Eigen::Index col, int count = 1) {
    if (replay_) {
      const int* rows = jac_.innerIndexPtr();
      if (next_ < slots_.size()) {
        const int k = slots_[next_];
        if (rows[k] == row && rows[k + count - 1] == row + count - 1) {
          ++next_;
          return jac_.valuePtr() + k;
        }
      }
      replay_ = false;
      broken_ = true;
    }
    const int k = entries(jac_, row, col, count);
    if (!broken_) slots_.push_back(k);
    return jac_.valuePtr() + k;
  }

 private:
  Eigen::SparseMatrix<double>& jac_;
  std::vector<int>& slots_;
  bool replay_ = false, broken_ = false;
  std::size_t next_ = 0;
};

// SlotWriter's kept places replayed from one of them on, by one thread: a body's writes,
// its first place kept with the places. A write whose rows do not match marks the cursor
// failed and lands in a scratch buffer (the caller then writes everything afresh).
class SlotCursor {
 public:
  SlotCursor(Eigen::SparseMatrix<double>& jac, const std::vector<int>& slots, std::size_t from)
      : values_(jac.valuePtr()), rows_(jac.innerIndexPtr()), slots_(slots), next_(from) {}
  double* at(Eigen::Index row, Eigen::Index, int count = 1) {
    if (next_ < slots_.size() && count <= static_cast<int>(sizeof scratch_ / sizeof(double))) {
      const int k = slots_[next_];
      if (rows_[k] == row && rows_[k + count - 1] == row + count - 1) {
        ++next_;
        return values_ + k;
      }
    }
    failed_ = true;
    return scratch_;
  }
  std::size_t position() const { return next_; }
  bool failed() const { return failed_; }

 private:
  double* values_;
  const int* rows_;
  const std::vector<int>& slots_;
  std::size_t next_;
  bool failed_ = false;
  double scratch_[16];
};

}  // namespace mbsflow::jacobian_slots
