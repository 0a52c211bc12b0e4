#include "engine/parts/part_store.h"

#include <fcntl.h>
#include <openssl/evp.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <atomic>
#include <set>

namespace gk::engine {
namespace {

const std::set<std::string>& formats() {
  static const std::set<std::string> f = {"stl", "obj", "off", "ply", "gltf", "glb", "step", "stp", "brep", "iges", "igs"};
  return f;
}

bool fsync_directory(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

std::string hex(const unsigned char* data, unsigned int n) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < n; ++i) {
    out += digits[data[i] >> 4];
    out += digits[data[i] & 15];
  }
  return out;
}

Error storage_error(const std::string& what) { return {ErrorCode::kInternal, "storage", what}; }

}  // namespace

bool is_supported_format(const std::string& format) { return formats().count(format) > 0; }

namespace {
// Names of one reader: the same bytes give the same part under either.
std::string canonical_format(const std::string& format) {
  if (format == "stp") return "step";
  if (format == "igs") return "iges";
  if (format == "glb") return "gltf";
  return format;
}
}  // namespace

bool is_part_id(const std::string& id) {
  return id.size() == 64 && id.find_first_not_of("0123456789abcdef") == std::string::npos;
}

namespace {
Error same_bytes_other_format(const PartRecord& stored, const std::string& format) {
  return Error{ErrorCode::kFailedPrecondition, "header.format",
               "these bytes are already part " + stored.id + ", read as " + stored.format + "; read as " + format +
                   " they would be another geometry under the same id"};
}
}  // namespace
bool is_cad_format(const std::string& format) {
  return format == "step" || format == "stp" || format == "brep" || format == "iges" || format == "igs";
}

struct PartUpload::Hasher {
  EVP_MD_CTX* ctx = EVP_MD_CTX_new();
  Hasher() { EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr); }
  ~Hasher() { EVP_MD_CTX_free(ctx); }
  void add(const std::string& bytes) { EVP_DigestUpdate(ctx, bytes.data(), bytes.size()); }
  std::string digest() {
    unsigned char out[EVP_MAX_MD_SIZE];
    unsigned int n = 0;
    EVP_DigestFinal_ex(ctx, out, &n);
    return hex(out, n);
  }
};

PartUpload::~PartUpload() {
  if (fd_ >= 0) ::close(fd_);
  if (!finished_ && !tmp_path_.empty()) std::remove(tmp_path_.c_str());
}

Result<bool> PartUpload::append(const std::string& bytes) {
  if (received_ + bytes.size() > declared_size_)
    return invalid_argument("data", "more bytes than the declared size_bytes (" + std::to_string(declared_size_) + ")");
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + written, bytes.size() - written);
    if (n <= 0) return storage_error("cannot write the upload to disk");
    written += static_cast<std::size_t>(n);
  }
  hasher_->add(bytes);
  received_ += bytes.size();
  return true;
}

Result<std::unique_ptr<PartStore>> PartStore::open(const std::string& directory) {
  std::error_code ec;
  std::filesystem::create_directories(directory + "/parts", ec);
  std::filesystem::create_directories(directory + "/tmp", ec);
  if (ec) return storage_error("cannot create " + directory + ": " + ec.message());
  std::unique_ptr<PartStore> store(new PartStore());
  store->dir_ = directory;
  if (sqlite3_open((directory + "/gatekeeper.sqlite").c_str(), &store->db_) != SQLITE_OK)
    return storage_error("cannot open the part database in " + directory);
  const char* schema =
      "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA busy_timeout=5000;"
      "CREATE TABLE IF NOT EXISTS parts (id TEXT PRIMARY KEY, name TEXT, format TEXT, size INTEGER, triangles INTEGER,"
      " min_x REAL, min_y REAL, min_z REAL, max_x REAL, max_y REAL, max_z REAL, closed INTEGER,"
      " created TEXT DEFAULT CURRENT_TIMESTAMP);";
  char* err = nullptr;
  if (sqlite3_exec(store->db_, schema, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string message = err ? err : "unknown";
    sqlite3_free(err);
    return storage_error("cannot prepare the part database: " + message);
  }
  // Leftovers of uploads interrupted by a crash.
  for (const auto& entry : std::filesystem::directory_iterator(directory + "/tmp", ec)) std::filesystem::remove(entry.path(), ec);
  return store;
}

Result<std::unique_ptr<PartStore>> PartStore::open_read_only(const std::string& directory) {
  std::unique_ptr<PartStore> store(new PartStore());
  store->dir_ = directory;
  if (sqlite3_open_v2((directory + "/gatekeeper.sqlite").c_str(), &store->db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
    return storage_error("cannot open the part database in " + directory + " for reading");
  sqlite3_busy_timeout(store->db_, 5000);
  return store;
}

PartStore::~PartStore() {
  if (db_) sqlite3_close(db_);
}

Result<std::unique_ptr<PartUpload>> PartStore::begin(const std::string& name, const std::string& format,
                                                     std::uint64_t size_bytes, const std::string& sha256_hex) {
  if (!is_supported_format(format)) return invalid_argument("header.format", "unsupported format '" + format + "'");
  if (size_bytes == 0) return invalid_argument("header.size_bytes", "must be positive");
  if (size_bytes > kMaxPartBytes) return invalid_argument("header.size_bytes", "larger than the 2 GiB limit");
  if (!is_part_id(sha256_hex)) return invalid_argument("header.sha256", "must be 64 lower-case hex digits");
  if (auto stored = get(sha256_hex); stored.ok() && canonical_format(stored.value().format) != canonical_format(format))
    return same_bytes_other_format(stored.value(), format);
  std::unique_ptr<PartUpload> upload(new PartUpload());
  static std::atomic<unsigned long long> counter{0};
  upload->tmp_path_ = dir_ + "/tmp/upload-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  upload->fd_ = ::open(upload->tmp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (upload->fd_ < 0) return storage_error("cannot create a temporary file");
  upload->declared_size_ = size_bytes;
  upload->declared_sha_ = sha256_hex;
  upload->name_ = name;
  upload->format_ = format;
  upload->hasher_ = std::make_unique<PartUpload::Hasher>();
  return upload;
}

Result<PartRecord> PartStore::finish(std::unique_ptr<PartUpload> upload,
                                     const std::function<Result<PartRecord>(const std::string&, PartRecord)>& describe) {
  if (upload->received_ != upload->declared_size_)
    return invalid_argument("data", "received " + std::to_string(upload->received_) + " bytes, header declared " +
                                        std::to_string(upload->declared_size_));
  const std::string sha = upload->hasher_->digest();
  if (sha != upload->declared_sha_) return invalid_argument("header.sha256", "does not match the content (got " + sha + ")");
  if (::fsync(upload->fd_) != 0) return storage_error("fsync failed");
  ::close(upload->fd_);
  upload->fd_ = -1;

  PartRecord record;
  record.id = sha;
  record.name = upload->name_;
  record.format = upload->format_;
  record.size_bytes = upload->declared_size_;
  const std::string final_path = dir_ + "/parts/" + sha + "." + record.format;
  // The content is checked before it is recorded: a broken file is rejected, not stored.
  auto described = describe(upload->tmp_path_, record);
  if (!described.ok()) return described.error();
  record = described.value();

  std::lock_guard<std::mutex> lock(mutex_);
  // The same bytes again: the part stands as stored (read as another format they would be
  // another geometry under the same id).
  if (auto stored = get_locked(sha); stored.ok()) {
    if (canonical_format(stored.value().format) != canonical_format(record.format)) return same_bytes_other_format(stored.value(), record.format);
    return stored.value();
  }
  if (std::rename(upload->tmp_path_.c_str(), final_path.c_str()) != 0) return storage_error("cannot move the upload into place");
  upload->finished_ = true;
  if (!fsync_directory(dir_ + "/parts")) return storage_error("cannot fsync the part directory");
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_,
                     "INSERT OR REPLACE INTO parts (id, name, format, size, triangles, min_x, min_y, min_z, max_x, max_y, max_z,"
                     " closed) VALUES (?,?,?,?,?,?,?,?,?,?,?,?)",
                     -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, record.id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 2, record.name.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 3, record.format.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_int64(stmt, 4, static_cast<sqlite3_int64>(record.size_bytes));
  sqlite3_bind_int64(stmt, 5, record.triangles);
  for (int k = 0; k < 3; ++k) {
    sqlite3_bind_double(stmt, 6 + k, record.bounds_min[k]);
    sqlite3_bind_double(stmt, 9 + k, record.bounds_max[k]);
  }
  sqlite3_bind_int(stmt, 12, record.closed ? 1 : 0);
  const int rc = sqlite3_step(stmt);
  sqlite3_finalize(stmt);
  if (rc != SQLITE_DONE) return storage_error("cannot record the part");
  return record;
}

Result<PartRecord> PartStore::get(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return get_locked(id);
}

Result<PartRecord> PartStore::get_locked(const std::string& id) const {
  // Checked before SQLite sees it, which would read an id only up to a NUL byte.
  if (!is_part_id(id)) return invalid_argument("part_id", "must be the 64 lower-case hex digits of a sha256");
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "SELECT id, name, format, size, triangles, min_x, min_y, min_z, max_x, max_y, max_z, closed "
                          "FROM parts WHERE id = ?", -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, id.c_str(), -1, SQLITE_TRANSIENT);
  Result<PartRecord> out = Error{ErrorCode::kNotFound, "part_id", "no part with id '" + id + "'"};
  if (sqlite3_step(stmt) == SQLITE_ROW) {
    PartRecord r;
    r.id = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    r.name = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1));
    r.format = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 2));
    r.size_bytes = static_cast<std::uint64_t>(sqlite3_column_int64(stmt, 3));
    r.triangles = static_cast<std::uint32_t>(sqlite3_column_int64(stmt, 4));
    for (int k = 0; k < 3; ++k) {
      r.bounds_min[k] = sqlite3_column_double(stmt, 5 + k);
      r.bounds_max[k] = sqlite3_column_double(stmt, 8 + k);
    }
    r.closed = sqlite3_column_int(stmt, 11) != 0;
    out = r;
  }
  sqlite3_finalize(stmt);
  return out;
}

std::string PartStore::path_of(const PartRecord& record) const { return dir_ + "/parts/" + record.id + "." + record.format; }

std::uint64_t PartStore::count() const {
  std::lock_guard<std::mutex> lock(mutex_);
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "SELECT COUNT(*) FROM parts", -1, &stmt, nullptr);
  std::uint64_t n = 0;
  if (sqlite3_step(stmt) == SQLITE_ROW) n = static_cast<std::uint64_t>(sqlite3_column_int64(stmt, 0));
  sqlite3_finalize(stmt);
  return n;
}

}  // namespace gk::engine
