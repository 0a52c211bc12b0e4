#include "engine/parts/packed_mesh_file.h"

#include "engine/parts/bvh_cache.h"
#include "kernel/bvh/mesh_pack.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <thread>

namespace gk::engine {
namespace {

Error file_error(const std::string& path, const std::string& why) { return invalid_argument("packed mesh " + path, why); }

bool same_box(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

// Opens a regular file for reading without blocking on anything else (a FIFO put there).
int open_regular(const std::string& path, struct stat& st) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return -1;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    errno = EINVAL;
    return -1;
  }
  return fd;
}

// The file there is this pack: the same size and the same closing checksum.
bool same_pack_there(const PackedMeshFile& file) {
  struct stat st {};
  const int fd = open_regular(file.path, st);
  if (fd < 0) return false;
  char tail[16];
  const bool same = static_cast<std::uint64_t>(st.st_size) == file.bytes && file.bytes >= sizeof tail &&
                    ::pread(fd, tail, sizeof tail, static_cast<off_t>(file.bytes - sizeof tail)) == static_cast<ssize_t>(sizeof tail) &&
                    std::memcmp(tail, &file.checksum.low, 8) == 0 && std::memcmp(tail + 8, &file.checksum.high, 8) == 0;
  ::close(fd);
  return same;
}

}  // namespace

Result<PackedMeshFile> write_packed_mesh(const MeshBvh& bvh, const std::string& directory) {
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  PackedMeshFile file;
  file.path = directory + "/" + mesh_content_hash(bvh.mesh()).hex() + ".pack";
  file.bounds = bvh.root_bounds();
  file.triangles = bvh.mesh().triangle_count();
  // One buffer per writing thread, kept between packs of ordinary size: fresh pages for every
  // pack are faulted in one by one. A buffer grown for a large part (over 16 MB, about 330,000
  // triangles) is given back after it: what is kept stays outside any memory budget.
  constexpr std::size_t kKeptBufferBytes = std::size_t{16} << 20;
  thread_local std::string bytes;
  struct GiveBackHuge {
    std::string& b;
    ~GiveBackHuge() {
      if (b.capacity() > kKeptBufferBytes) std::string().swap(b);
    }
  } give_back{bytes};
  pack_mesh_bvh(bvh, bytes);
  file.bytes = bytes.size();
  file.checksum = pack_checksum(bytes);
  if (same_pack_there(file)) return file;
  std::ostringstream tmp;
  tmp << file.path << ".tmp." << ::getpid() << "." << std::this_thread::get_id();
  const int fd = ::open(tmp.str().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return file_error(tmp.str(), std::string("cannot be created: ") + std::strerror(errno));
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    written += static_cast<std::size_t>(n);
  }
  const bool closed = ::close(fd) == 0;
  if (written != bytes.size() || !closed) {
    std::filesystem::remove(tmp.str(), ec);
    return file_error(tmp.str(), "could not be written whole");
  }
  std::filesystem::rename(tmp.str(), file.path, ec);
  if (ec) {
    std::filesystem::remove(tmp.str(), ec);
    return file_error(file.path, "could not be renamed into place");
  }
  return file;
}

Result<std::shared_ptr<const MeshBvh>> read_packed_mesh(const PackedMeshFile& file) {
  struct stat st {};
  const int fd = open_regular(file.path, st);
  if (fd < 0) return file_error(file.path, std::string("cannot be opened as a regular file: ") + std::strerror(errno));
  if (static_cast<std::uint64_t>(st.st_size) != file.bytes) {
    ::close(fd);
    return file_error(file.path, "is not the size it was written with (" + std::to_string(file.bytes) + " bytes)");
  }
  // Mapped, not read: the page cache's pages are used in place (no copy into a buffer), and the
  // mapping starts page-aligned, so the arrays are copied straight into the mesh and tree.
  void* mapped = file.bytes == 0 ? MAP_FAILED
                                 : ::mmap(nullptr, static_cast<std::size_t>(file.bytes), PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
  ::close(fd);
  if (mapped == MAP_FAILED) return file_error(file.path, std::string("cannot be mapped: ") + std::strerror(errno));
  const std::string_view bytes(static_cast<const char*>(mapped), static_cast<std::size_t>(file.bytes));
  if (pack_checksum(bytes) != file.checksum) {
    ::munmap(mapped, static_cast<std::size_t>(file.bytes));
    return file_error(file.path, "is not the pack written for this object (another mesh's, or written again since)");
  }
  auto bvh = unpack_mesh_bvh(bytes);
  ::munmap(mapped, static_cast<std::size_t>(file.bytes));
  if (!bvh.ok()) return file_error(file.path, bvh.error().to_string());
  const MeshBvh& b = *bvh.value();
  if (b.mesh().triangle_count() != file.triangles || !same_box(b.root_bounds(), file.bounds))
    return file_error(file.path, "holds another mesh than the one described (triangle count or bounds differ)");
  return std::shared_ptr<const MeshBvh>(bvh.value());
}

}  // namespace gk::engine
