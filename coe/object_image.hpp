// The value image of one object (ETG.1000.6 §5.6.2.1.4 complete-access layout, see
// object_dictionary.hpp): its bytes, zero-filled when sized. Most objects of a device are a
// single entry of 1 to 8 bytes, so images that small live inside the object itself; larger ones
// take one heap block. Sized at start-up only (the request path reads and writes bytes in place).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace rackcat::coe {

class ObjectImage {
 public:
  static constexpr size_t kInline = 8;

  ObjectImage() = default;
  ObjectImage(const ObjectImage& other) { copy_from(other); }
  ObjectImage& operator=(const ObjectImage& other) {
    if (this != &other) {
      release();
      copy_from(other);
    }
    return *this;
  }
  ObjectImage(ObjectImage&& other) noexcept { take(other); }
  ObjectImage& operator=(ObjectImage&& other) noexcept {
    if (this != &other) {
      release();
      take(other);
    }
    return *this;
  }
  ~ObjectImage() { release(); }

  // `bytes` zero bytes (the previous content is dropped). Allocates above kInline.
  void assign_zero(size_t bytes) {
    release();
    if (bytes > kInline) heap_ = new uint8_t[bytes];
    size_ = bytes;
    std::memset(data(), 0, bytes);
  }

  uint8_t* data() { return size_ > kInline ? heap_ : inline_; }
  const uint8_t* data() const { return size_ > kInline ? heap_ : inline_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  uint8_t& operator[](size_t i) { return data()[i]; }
  uint8_t operator[](size_t i) const { return data()[i]; }
  std::span<uint8_t> span() { return {data(), size_}; }
  std::span<const uint8_t> span() const { return {data(), size_}; }

 private:
  void release() {
    if (size_ > kInline) delete[] heap_;
    size_ = 0;
    std::memset(inline_, 0, kInline);
  }
  void copy_from(const ObjectImage& other) {
    size_ = 0;
    if (other.size_ > kInline) heap_ = new uint8_t[other.size_];
    size_ = other.size_;
    if (size_ != 0) std::memcpy(data(), other.data(), size_);
  }
  void take(ObjectImage& other) {
    size_ = other.size_;
    if (size_ > kInline) {
      heap_ = other.heap_;
    } else {
      std::memcpy(inline_, other.inline_, kInline);
    }
    other.size_ = 0;
    std::memset(other.inline_, 0, kInline);
  }

  size_t size_ = 0;
  union {
    uint8_t inline_[kInline] = {};
    uint8_t* heap_;
  };
};

}  // namespace rackcat::coe
