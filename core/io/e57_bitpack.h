// E57 bytestreams of bit-packed integers (ASTM E2807 §9.7): each value takes a fixed number of
// bits, least significant bit first, packed back to back across bytes and across data packets.
// Float streams use the same reader with 32 or 64 bits per value.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace scanreg::io::e57 {

// Number of bits an integer in [minimum, maximum] takes: ceil(log2(maximum - minimum + 1)).
inline int BitWidth(std::int64_t minimum, std::int64_t maximum) {
  const std::uint64_t range = static_cast<std::uint64_t>(maximum) - static_cast<std::uint64_t>(minimum);
  return range == 0 ? 0 : 64 - __builtin_clzll(range);
}

// Reads a bytestream fed piece by piece, as its parts arrive in successive data packets. A value
// may span pieces; Read() fails (consuming nothing it cannot give back later) until enough
// bytes have been appended.
class BitReader {
 public:
  void Append(std::string_view bytes) {
    if (offset_ > 0 && offset_ >= data_.size() / 2) {
      data_.erase(0, offset_);
      offset_ = 0;
    }
    data_.append(bytes.data(), bytes.size());
  }
  std::uint64_t AvailableBits() const { return std::uint64_t(have_) + 8 * (data_.size() - offset_); }
  // The next `bits` (0..64) bits as an unsigned value; false when fewer bits are available.
  bool Read(int bits, std::uint64_t* value) {
    if (AvailableBits() < std::uint64_t(bits)) return false;
    if (bits <= 32) return ReadSmall(bits, value);
    std::uint64_t low = 0, high = 0;
    ReadSmall(32, &low);
    ReadSmall(bits - 32, &high);
    *value = low | (high << 32);
    return true;
  }

 private:
  bool ReadSmall(int bits, std::uint64_t* value) {
    if (have_ < bits && data_.size() - offset_ >= 8) {
      // Refill with one 8-byte load. Bits loaded past the whole bytes taken are the stream's
      // next bits, so loading them again later (OR) changes nothing.
      std::uint64_t word = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
      std::memcpy(&word, data_.data() + offset_, 8);
#else
      for (int k = 0; k < 8; ++k) word |= std::uint64_t(static_cast<unsigned char>(data_[offset_ + k])) << (8 * k);
#endif
      acc_ |= word << have_;
      const int take = (63 - have_) >> 3;
      offset_ += take;
      have_ += 8 * take;
    }
    while (have_ < bits) {
      acc_ |= std::uint64_t(static_cast<unsigned char>(data_[offset_++])) << have_;
      have_ += 8;
    }
    *value = bits == 0 ? 0 : acc_ & (~std::uint64_t(0) >> (64 - bits));
    acc_ = bits == 64 ? 0 : acc_ >> bits;
    have_ -= bits;
    return true;
  }

  std::string data_;
  std::size_t offset_ = 0;
  std::uint64_t acc_ = 0;
  int have_ = 0;
};

// Packs values LSB first; Take() returns the whole bytes written so far (the last partial byte
// zero-padded when flush is true).
class BitWriter {
 public:
  void Write(std::uint64_t value, int bits) {
    if (bits > 32) {
      Write(value & 0xFFFFFFFFu, 32);
      Write(value >> 32, bits - 32);
      return;
    }
    if (bits == 0) return;
    acc_ |= (value & (~std::uint64_t(0) >> (64 - bits))) << have_;
    have_ += bits;
    while (have_ >= 8) {
      bytes_.push_back(static_cast<char>(acc_ & 0xFF));
      acc_ >>= 8;
      have_ -= 8;
    }
  }
  std::string Take(bool flush) {
    if (flush && have_ > 0) {
      bytes_.push_back(static_cast<char>(acc_ & 0xFF));
      acc_ = 0;
      have_ = 0;
    }
    std::string out;
    out.swap(bytes_);
    return out;
  }

 private:
  std::string bytes_;
  std::uint64_t acc_ = 0;
  int have_ = 0;
};

}  // namespace scanreg::io::e57
