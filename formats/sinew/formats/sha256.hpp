#pragma once
// SHA-256 (FIPS 180-4) of byte strings and files, as lowercase hex. Used for the provenance of
// model files: every input file is recorded with its digest.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace sinew::formats {

// Incremental SHA-256: update() any number of times, then hex_digest() once.
class Sha256 {
 public:
  Sha256();
  void update(const void* data, std::size_t size);
  void update(std::string_view data) { update(data.data(), data.size()); }
  // Finishes the hash and returns the 64-character lowercase hex digest. The object must not be
  // updated afterwards.
  std::string hex_digest();

 private:
  void compress(const std::uint8_t* block);
  std::array<std::uint32_t, 8> state_;
  std::array<std::uint8_t, 64> buffer_{};
  std::size_t buffered_ = 0;
  std::uint64_t total_bytes_ = 0;
};

// SHA-256 of a byte string, lowercase hex.
std::string sha256_hex(std::string_view data);
// SHA-256 of a file's contents, lowercase hex. Throws IoError when it cannot be read.
std::string sha256_file(const std::string& path);
// True when `s` is 64 lowercase hex characters.
bool is_sha256_hex(std::string_view s);

}  // namespace sinew::formats
