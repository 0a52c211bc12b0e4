// Durable, content-addressed part storage: a file per part named by its sha256, written to a
// temporary file, fsync'd and renamed; metadata in SQLite (WAL, synchronous FULL). A part is
// acknowledged only after both are on disk, so a restart or kill -9 keeps every acknowledged part.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

struct sqlite3;

namespace gk::engine {

struct PartRecord {
  std::string id;  // sha256, lower-case hex
  std::string name;
  std::string format;
  std::uint64_t size_bytes = 0;
  std::uint32_t triangles = 0;
  Vec3 bounds_min = Vec3::Zero(), bounds_max = Vec3::Zero();
  bool closed = false;
};

class PartStore;

// One upload in progress: bytes go to a private temporary file as they arrive.
class PartUpload {
 public:
  ~PartUpload();  // an unfinished upload leaves nothing behind
  Result<bool> append(const std::string& bytes);
  std::uint64_t received() const { return received_; }
  const std::string& format() const { return format_; }

 private:
  friend class PartStore;
  PartUpload() = default;
  std::string tmp_path_;
  int fd_ = -1;
  std::uint64_t received_ = 0;
  std::uint64_t declared_size_ = 0;
  std::string declared_sha_;
  std::string name_, format_;
  struct Hasher;
  std::unique_ptr<Hasher> hasher_;
  bool finished_ = false;
};

class PartStore {
 public:
  static Result<std::unique_ptr<PartStore>> open(const std::string& directory);
  // For a batch program reading a daemon's data directory beside it (the MPI audit driver): reads
  // only, and leaves the temporary files of the daemon's uploads in progress alone.
  static Result<std::unique_ptr<PartStore>> open_read_only(const std::string& directory);
  ~PartStore();

  static constexpr std::uint64_t kMaxPartBytes = 2ull << 30;  // 2 GiB

  // Starts an upload; the header is validated (format, size, sha256 syntax).
  Result<std::unique_ptr<PartUpload>> begin(const std::string& name, const std::string& format,
                                            std::uint64_t size_bytes, const std::string& sha256_hex);
  // Checks size and sha256, then makes the file durable. `describe` fills triangles and bounds
  // from the durable file (it may reject the content: nothing is then recorded).
  Result<PartRecord> finish(std::unique_ptr<PartUpload> upload,
                            const std::function<Result<PartRecord>(const std::string& path, PartRecord)>& describe);

  Result<PartRecord> get(const std::string& id) const;  // id: a sha256 in hex, else INVALID_ARGUMENT
  std::string path_of(const PartRecord& record) const;
  std::uint64_t count() const;

 private:
  PartStore() = default;
  std::string dir_;
  sqlite3* db_ = nullptr;
  Result<PartRecord> get_locked(const std::string& id) const;
  mutable std::mutex mutex_;
};

bool is_supported_format(const std::string& format);
bool is_cad_format(const std::string& format);
bool is_part_id(const std::string& id);  // 64 lower-case hex digits (a sha256)

}  // namespace gk::engine
