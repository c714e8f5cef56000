#pragma once
// Members that most items leave at their defaults, held behind one pointer so that a
// million such items stay small: they read as the default while empty and copy as values.
#include <atomic>
#include <cstddef>
#include <cstring>
#include <memory>
#include <utility>

namespace mbsflow {

namespace detail {
// A pointer that owns what it points to and copies it with itself.
template <class T>
class CopiedPtr {
 public:
  CopiedPtr() = default;
  CopiedPtr(const CopiedPtr& o) : p_(o.p_ ? std::make_unique<T>(*o.p_) : nullptr) {}
  CopiedPtr& operator=(const CopiedPtr& o) {
    if (this != &o) p_ = o.p_ ? std::make_unique<T>(*o.p_) : nullptr;
    return *this;
  }
  CopiedPtr(CopiedPtr&&) noexcept = default;
  CopiedPtr& operator=(CopiedPtr&&) noexcept = default;

  T* get() const { return p_.get(); }
  T& emplace(const T& value = T{}) { return *(p_ = std::make_unique<T>(value)); }
  void reset() { p_.reset(); }

 private:
  std::unique_ptr<T> p_;
};
}  // namespace detail

// A struct member (a joint's motor and limits): reads as T{} while empty, and makes room
// when written through edit().
template <class T>
class RareValue {
 public:
  const T& get() const { return p_.get() ? *p_.get() : fallback(); }
  const T* operator->() const { return &get(); }
  T& edit() { return p_.get() ? *p_.get() : p_.emplace(); }

 private:
  static const T& fallback() {
    static const T value{};
    return value;
  }
  detail::CopiedPtr<T> p_;
};

// A plain value that most items leave at one value, Default (a joint's frames, preload,
// points, stiffness and damping): it reads as a const T& and assigns from a T, like the
// member it stands for, and holds one pointer. While it equals Default (bit for bit) the
// pointer is null; otherwise it points to the value, which copies of the item share
// (counted, never changed in place: assigning gives this item a node of its own). share()
// makes an item that holds the same value as another take the other's node, so that a
// million joints with one stiffness store it once (a joint was 256 bytes as values).
template <class T, const T& Default>
class Defaulted {
 public:
  Defaulted() = default;
  Defaulted(const T& value) { *this = value; }  // NOLINT: initialises like a T
  Defaulted(const Defaulted& o) noexcept : n_(o.n_) {
    if (n_) n_->refs.fetch_add(1, std::memory_order_relaxed);
  }
  Defaulted(Defaulted&& o) noexcept : n_(std::exchange(o.n_, nullptr)) {}
  Defaulted& operator=(const Defaulted& o) noexcept {
    Defaulted(o).swap(*this);
    return *this;
  }
  Defaulted& operator=(Defaulted&& o) noexcept {
    Defaulted(std::move(o)).swap(*this);
    return *this;
  }
  ~Defaulted() { release(); }
  Defaulted& operator=(const T& value) {
    if (same_bits(value, get())) return *this;
    Node* n = same_bits(value, Default) ? nullptr : new Node{{1}, value};
    release();
    n_ = n;
    return *this;
  }
  // One element changed (the others kept), as `member[i] = x` would.
  template <class X>
  void set(std::size_t i, const X& x) {
    T v = get();
    v[i] = x;
    *this = v;
  }
  // Takes o's node if o holds the same value, bit for bit.
  void share(const Defaulted& o) {
    if (n_ != o.n_ && same_bits(get(), o.get())) *this = o;
  }
  bool is_default() const { return n_ == nullptr; }

  const T& get() const { return n_ ? n_->value : Default; }
  operator const T&() const { return get(); }  // NOLINT: reads like a T
  auto operator[](std::size_t i) const { return get()[i]; }
  auto begin() const { return get().begin(); }
  auto end() const { return get().end(); }
  friend bool operator==(const Defaulted& a, const Defaulted& b) { return a.get() == b.get(); }
  friend bool operator==(const Defaulted& a, const T& b) { return a.get() == b; }

 private:
  struct Node {
    std::atomic<std::size_t> refs;
    T value;
  };
  static bool same_bits(const T& a, const T& b) { return std::memcmp(&a, &b, sizeof(T)) == 0; }
  void swap(Defaulted& o) noexcept { std::swap(n_, o.n_); }
  void release() noexcept {
    if (n_ && n_->refs.fetch_sub(1, std::memory_order_acq_rel) == 1) delete n_;
    n_ = nullptr;
  }
  Node* n_ = nullptr;
};

// The last few distinct values of one field over the items made so far, each offered to
// the next item's field (Defaulted::share): items written one after another with the same
// value (a generated chain's joints, a file's) then share one node. A value found moves one
// place up, and a new one takes the first free place or else the last, so that the values
// most items repeat stay while one-off values (a grid's clamps) replace each other.
template <class D, int N = 8>
class RecentValues {
 public:
  void share(D& d) {
    if (d.is_default()) return;
    int i = 0;
    for (; i < N && !recent_[i].is_default(); ++i) {
      d.share(recent_[i]);
      if (&d.get() == &recent_[i].get()) {
        if (i > 0) std::swap(recent_[i], recent_[i - 1]);
        return;
      }
    }
    recent_[i < N ? i : N - 1] = d;
  }

 private:
  D recent_[N];
};

}  // namespace mbsflow
