#pragma once
// Members that most items leave at their defaults, held behind one pointer so that a
// million such items stay small: they read as the default while empty and copy as values.
#include <cstddef>
#include <memory>

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

// A plain value that most items leave at one value, Default (a joint's frames and preload):
// it reads as a const T& and assigns from a T, like the member it stands for, and holds
// only a pointer while it equals Default (a million joints' frames and preloads take
// 24 MB so, 112 MB as values).
template <class T, const T& Default>
class Defaulted {
 public:
  Defaulted() = default;
  Defaulted(const T& value) { *this = value; }  // NOLINT: initialises like a T
  Defaulted& operator=(const T& value) {
    if (value == Default)
      p_.reset();
    else if (T* p = p_.get())
      *p = value;
    else
      p_.emplace(value);
    return *this;
  }

  const T& get() const { return p_.get() ? *p_.get() : Default; }
  operator const T&() const { return get(); }  // NOLINT: reads like a T
  auto operator[](std::size_t i) const { return get()[i]; }
  friend bool operator==(const Defaulted& a, const Defaulted& b) { return a.get() == b.get(); }
  friend bool operator==(const Defaulted& a, const T& b) { return a.get() == b; }

 private:
  detail::CopiedPtr<T> p_;
};

}  // namespace mbsflow
