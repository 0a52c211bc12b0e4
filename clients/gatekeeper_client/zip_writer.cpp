#include "clients/gatekeeper_client/zip_writer.h"

#include <array>
#include <stdexcept>

namespace gk::client {
namespace {

void put16(std::string& out, std::uint32_t v) {
  out.push_back(static_cast<char>(v & 0xFF));
  out.push_back(static_cast<char>((v >> 8) & 0xFF));
}
void put32(std::string& out, std::uint32_t v) {
  put16(out, v & 0xFFFF);
  put16(out, v >> 16);
}

}  // namespace

std::uint32_t crc32_of(const std::string& bytes) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char byte : bytes) c = table[(c ^ byte) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

void ZipWriter::add(const std::string& name, const std::string& content) {
  // Entries past 65,535 are counted in the zip64 end records; every offset and size must still
  // fit 32 bits (4 GiB: about a million BCF topics), which this writer does not go beyond.
  if (body_.size() + content.size() + name.size() + 30 > 0xFFFFFFFFull)
    throw std::length_error("the archive would exceed 4 GiB, which this zip writer does not write");
  Entry e{name, crc32_of(content), static_cast<std::uint32_t>(content.size()), static_cast<std::uint32_t>(body_.size())};
  put32(body_, 0x04034b50);  // local file header
  put16(body_, 20);          // version needed: 2.0
  put16(body_, 1u << 11);    // names are UTF-8
  put16(body_, 0);           // stored
  put16(body_, time_);
  put16(body_, date_);
  put32(body_, e.crc);
  put32(body_, e.size);
  put32(body_, e.size);
  put16(body_, static_cast<std::uint32_t>(name.size()));
  put16(body_, 0);
  body_ += name;
  body_ += content;
  entries_.push_back(std::move(e));
}

std::string ZipWriter::finish() const {
  std::string out = body_;
  const auto directory_offset = static_cast<std::uint32_t>(out.size());
  for (const Entry& e : entries_) {
    put32(out, 0x02014b50);  // central directory header
    put16(out, 20);          // made by: 2.0
    put16(out, 20);
    put16(out, 1u << 11);
    put16(out, 0);
    put16(out, time_);
    put16(out, date_);
    put32(out, e.crc);
    put32(out, e.size);
    put32(out, e.size);
    put16(out, static_cast<std::uint32_t>(e.name.size()));
    put16(out, 0);  // extra
    put16(out, 0);  // comment
    put16(out, 0);  // disk
    put16(out, 0);  // internal attributes
    put32(out, 0);  // external attributes
    put32(out, e.offset);
    out += e.name;
  }
  const std::uint64_t directory_size = out.size() - directory_offset;
  if (out.size() > 0xFFFFFFFFull) throw std::length_error("the archive would exceed 4 GiB, which this zip writer does not write");
  const bool zip64 = entries_.size() > 0xFFFE;
  if (zip64) {
    const std::uint64_t zip64_end = out.size();
    const auto put64 = [&](std::uint64_t v) {
      put32(out, static_cast<std::uint32_t>(v & 0xFFFFFFFFu));
      put32(out, static_cast<std::uint32_t>(v >> 32));
    };
    put32(out, 0x06064b50);  // zip64 end of central directory
    put64(44);               // its size after this field
    put16(out, 45);          // made by: 4.5 (zip64)
    put16(out, 45);
    put32(out, 0);
    put32(out, 0);
    put64(entries_.size());
    put64(entries_.size());
    put64(directory_size);
    put64(directory_offset);
    put32(out, 0x07064b50);  // its locator
    put32(out, 0);
    put64(zip64_end);
    put32(out, 1);
  }
  const std::uint32_t count = zip64 ? 0xFFFFu : static_cast<std::uint32_t>(entries_.size());
  put32(out, 0x06054b50);  // end of central directory
  put16(out, 0);
  put16(out, 0);
  put16(out, count);
  put16(out, count);
  put32(out, static_cast<std::uint32_t>(directory_size));
  put32(out, directory_offset);
  put16(out, 0);
  return out;
}

}  // namespace gk::client
