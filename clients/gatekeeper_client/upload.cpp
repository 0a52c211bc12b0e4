#include "clients/gatekeeper_client/upload.h"

#include <openssl/evp.h>

#include <cctype>
#include <filesystem>

namespace gk::client {

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &n, EVP_sha256(), nullptr);
  static const char* const kHex = "0123456789abcdef";
  std::string hex;
  for (unsigned int i = 0; i < n; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  return hex;
}

std::string format_of(const std::string& path) {
  std::string format = std::filesystem::path(path).extension().string();
  if (!format.empty()) format = format.substr(1);
  for (char& c : format) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return format;
}

grpc::Status upload_part(::gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& bytes, const UploadOptions& options,
                         ::gatekeeper::v1::PartInfo* info) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + options.deadline);
  auto writer = stub.UploadPart(&ctx, info);
  ::gatekeeper::v1::UploadPartChunk header;
  header.mutable_header()->set_name(options.name.empty() ? "part." + options.format : options.name);
  header.mutable_header()->set_format(options.format);
  header.mutable_header()->set_size_bytes(bytes.size());
  header.mutable_header()->set_sha256(options.declared_sha.empty() ? sha256_hex(bytes) : options.declared_sha);
  writer->Write(header);
  const std::size_t chunk = options.chunk_bytes > 0 ? options.chunk_bytes : 1u << 20;
  for (std::size_t at = 0; at < bytes.size(); at += chunk) {
    ::gatekeeper::v1::UploadPartChunk data;
    data.set_data(bytes.substr(at, chunk));
    if (!writer->Write(data)) break;  // the server ended the call: Finish says why
  }
  writer->WritesDone();
  return writer->Finish();
}

}  // namespace gk::client
