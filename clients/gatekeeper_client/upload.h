// Uploading a part: the header (name, format, size, sha256), then chunks of at most 1 MiB; the
// reply is the stored part's record (its id is the sha256).
#pragma once

#include "gatekeeper/v1/gatekeeper.grpc.pb.h"

#include <chrono>
#include <cstddef>
#include <string>

namespace gk::client {

struct UploadOptions {
  std::string name;          // empty: "part.<format>"
  std::string format;        // stl, obj, off, ply, gltf, glb, step, stp, iges, igs, brep
  std::string declared_sha;  // empty: the bytes' true sha256 (a test may declare another)
  std::size_t chunk_bytes = 1u << 20;
  std::chrono::seconds deadline{600};
};

grpc::Status upload_part(::gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& bytes, const UploadOptions& options,
                         ::gatekeeper::v1::PartInfo* info);

// The format a file's extension names, lower case ("" without one).
std::string format_of(const std::string& path);

// Lower-case hex sha256 of the bytes.
std::string sha256_hex(const std::string& bytes);

}  // namespace gk::client
