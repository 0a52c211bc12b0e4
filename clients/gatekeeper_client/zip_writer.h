// A zip archive of stored (uncompressed) entries, built in memory: what a BCF file (.bcfzip) is.
// Stored entries keep the writer a page long and need no compression library; BCF files are a
// few kilobytes of XML per topic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace gk::client {

class ZipWriter {
 public:
  // `dos_date`/`dos_time`: every entry's modification time, in MS-DOS form.
  ZipWriter(std::uint16_t dos_date, std::uint16_t dos_time) : date_(dos_date), time_(dos_time) {}
  void add(const std::string& name, const std::string& content);
  // The archive's bytes (local entries, central directory, end record).
  std::string finish() const;

 private:
  struct Entry {
    std::string name;
    std::uint32_t crc = 0, size = 0, offset = 0;
  };
  std::uint16_t date_, time_;
  std::string body_;
  std::vector<Entry> entries_;
};

// CRC-32 (IEEE 802.3, the zip format's).
std::uint32_t crc32_of(const std::string& bytes);

}  // namespace gk::client
