#pragma once
#include <atomic>
#include <memory>
#include <utility>

// A value that copies share until one of them changes it (copy on write): a copy costs a pointer,
// and write() copies the value only while another copy still holds it. objmap follow copies the
// object map at every publish while the live map goes on; only the objects that change meanwhile
// are copied. Safe across threads as objmap uses it: copies are made on one thread, and another
// thread's copy only ever lets go of the value (use_count never rises behind write()'s back).
namespace objmap {

template <class T>
class CopyOnWrite {
 public:
  CopyOnWrite() : value_(std::make_shared<T>()) {}
  CopyOnWrite(T value) : value_(std::make_shared<T>(std::move(value))) {}  // NOLINT: implicit
  CopyOnWrite& operator=(T value) {
    value_ = std::make_shared<T>(std::move(value));
    return *this;
  }

  const T& operator*() const { return *value_; }
  const T* operator->() const { return value_.get(); }
  // The value, this copy's own from now on.
  T& write() {
    if (value_.use_count() > 1) {
      value_ = std::make_shared<T>(*value_);
    } else {
      // The other copies' last reads of the value happen before this write.
      std::atomic_thread_fence(std::memory_order_acquire);
    }
    return *value_;
  }
  bool shared() const { return value_.use_count() > 1; }

 private:
  std::shared_ptr<T> value_;
};

}  // namespace objmap
