#include "server/access_control.h"

#include <grpcpp/security/auth_metadata_processor.h>
#include <grpcpp/security/server_credentials.h>
#include <openssl/bio.h>
#include <openssl/crypto.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <openssl/sha.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <array>
#include <fstream>
#include <optional>
#include <sstream>
#include <vector>

namespace gk::server {
namespace {

constexpr std::size_t kMinTokenLength = 16;
constexpr char kAuthorization[] = "authorization";
constexpr char kBearer[] = "Bearer ";

using Digest = std::array<unsigned char, SHA256_DIGEST_LENGTH>;

Digest digest_of(const char* data, std::size_t size) {
  Digest d{};
  SHA256(reinterpret_cast<const unsigned char*>(data), size, d.data());
  return d;
}

Result<std::string> read_private_file(const std::string& path, const std::string& option, bool must_be_private) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) return invalid_argument(option, "cannot read " + path);
  if (must_be_private && (st.st_mode & 077) != 0)
    return invalid_argument(option, path + " is readable by group or others (chmod 600 it)");
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  if (!in && !in.eof()) return invalid_argument(option, "cannot read " + path);
  return bytes.str();
}

// When the first certificate of a PEM chain is past its notAfter: that date; else nothing.
std::optional<std::string> certificate_expired(const std::string& pem) {
  BIO* bio = BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size()));
  if (!bio) return std::nullopt;
  X509* cert = PEM_read_bio_X509(bio, nullptr, nullptr, nullptr);
  BIO_free(bio);
  if (!cert) return std::nullopt;  // gRPC reports an unreadable certificate itself
  std::optional<std::string> out;
  const ASN1_TIME* not_after = X509_get0_notAfter(cert);
  if (X509_cmp_current_time(not_after) < 0) {
    BIO* text = BIO_new(BIO_s_mem());
    ASN1_TIME_print(text, not_after);
    char* data = nullptr;
    const long size = BIO_get_mem_data(text, &data);
    out = std::string(data, static_cast<std::size_t>(size));
    BIO_free(text);
  }
  X509_free(cert);
  return out;
}

struct TokenEntry {
  Digest digest;
  Role role;
};

// The tokens this process was configured with (set once, before serving); null: none.
std::shared_ptr<const std::vector<TokenEntry>>& configured_tokens() {
  static std::shared_ptr<const std::vector<TokenEntry>> tokens;
  return tokens;
}

// The entry of an "authorization" header's bearer token, or null. Every entry is compared, in
// constant time, so timing tells nothing about the tokens.
const TokenEntry* entry_of(const std::vector<TokenEntry>& tokens, const std::string& header) {
  const std::string prefix = kBearer;
  if (header.compare(0, prefix.size(), prefix) != 0) return nullptr;
  const Digest presented = digest_of(header.data() + prefix.size(), header.size() - prefix.size());
  const TokenEntry* match = nullptr;
  for (const TokenEntry& t : tokens)
    if (CRYPTO_memcmp(t.digest.data(), presented.data(), presented.size()) == 0) match = &t;
  return match;
}

Result<std::vector<TokenEntry>> read_tokens(const std::string& path) {
  auto text = read_private_file(path, "token_file", true);
  if (!text.ok()) return text.error();
  std::vector<TokenEntry> out;
  std::istringstream lines(text.value());
  std::string line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    std::istringstream words(line);
    std::string role, token, extra;
    if (!(words >> role) || role[0] == '#') continue;
    const std::string where = path + ":" + std::to_string(number);
    if (!(words >> token) || (words >> extra)) return invalid_argument("token_file", where + ": expected \"<role> <token>\"");
    Role r;
    if (role == "read") r = Role::kRead;
    else if (role == "write") r = Role::kWrite;
    else if (role == "admin") r = Role::kAdmin;
    else return invalid_argument("token_file", where + ": role must be read, write or admin");
    if (token.size() < kMinTokenLength)
      return invalid_argument("token_file", where + ": tokens must have at least " + std::to_string(kMinTokenLength) + " characters");
    out.push_back({digest_of(token.data(), token.size()), r});
  }
  if (out.empty()) return invalid_argument("token_file", path + " holds no token");
  return out;
}

// Runs before every call (health checks included) and refuses those without a known token. The
// role is not stored here: gRPC keeps an auth context per connection, and one connection carries
// the calls of every token a client (or proxy) holds — each call's own header decides its role
// (require_role), so the header is left in the call's metadata.
class TokenCheck final : public grpc::AuthMetadataProcessor {
 public:
  explicit TokenCheck(std::shared_ptr<const std::vector<TokenEntry>> tokens) : tokens_(std::move(tokens)) {}
  bool IsBlocking() const override { return false; }

  grpc::Status Process(const InputMetadata& metadata, grpc::AuthContext*, OutputMetadata*, OutputMetadata*) override {
    const auto found = metadata.find(kAuthorization);
    if (found == metadata.end()) return {grpc::StatusCode::UNAUTHENTICATED, "a bearer token is required (authorization: Bearer <token>)"};
    if (!entry_of(*tokens_, std::string(found->second.data(), found->second.size())))
      return {grpc::StatusCode::UNAUTHENTICATED, "unknown bearer token (expected authorization: Bearer <token>)"};
    return grpc::Status::OK;
  }

 private:
  std::shared_ptr<const std::vector<TokenEntry>> tokens_;
};

}  // namespace

const char* to_string(Role role) {
  switch (role) {
    case Role::kRead: return "read";
    case Role::kWrite: return "write";
    case Role::kAdmin: return "admin";
  }
  return "read";
}

bool is_loopback_listen_address(const std::string& listen) {
  const std::size_t colon = listen.rfind(':');
  std::string host = colon == std::string::npos ? listen : listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  if (host == "localhost" || host == "::1") return true;
  if (host.rfind("127.", 0) != 0) return false;
  // 127.a.b.c with numbers only
  int dots = 0;
  for (char c : host) {
    if (c == '.') ++dots;
    else if (c < '0' || c > '9') return false;
  }
  return dots == 3;
}

Result<std::shared_ptr<grpc::ServerCredentials>> server_credentials(const AccessOptions& options) {
  std::shared_ptr<grpc::ServerCredentials> creds;
  const bool tls = !options.tls_cert_file.empty() || !options.tls_key_file.empty();
  if (tls) {
    if (options.tls_cert_file.empty() || options.tls_key_file.empty())
      return invalid_argument(options.tls_cert_file.empty() ? "tls_cert" : "tls_key", "TLS needs both a certificate and its key");
    auto cert = read_private_file(options.tls_cert_file, "tls_cert", false);
    if (!cert.ok()) return cert.error();
    if (auto expired = certificate_expired(cert.value()); expired)
      return invalid_argument("tls_cert", options.tls_cert_file + " has expired (" + *expired + "): clients would refuse it");
    auto key = read_private_file(options.tls_key_file, "tls_key", true);
    if (!key.ok()) return key.error();
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back({key.value(), cert.value()});
    if (!is_loopback_listen_address(options.listen) && options.tls_client_ca.empty() && options.token_file.empty())
      return invalid_argument("listen", options.listen + " is beyond loopback: TLS alone lets anybody call; require client "
                                                         "certificates (--tls-client-ca) or bearer tokens (--token-file)");
    if (!options.tls_client_ca.empty()) {
      auto ca = read_private_file(options.tls_client_ca, "tls_client_ca", false);
      if (!ca.ok()) return ca.error();
      ssl.pem_root_certs = ca.value();
      ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
    }
    creds = grpc::SslServerCredentials(ssl);
  } else {
    if (!options.tls_client_ca.empty()) return invalid_argument("tls_client_ca", "needs --tls-cert and --tls-key");
    if (!is_loopback_listen_address(options.listen))
      return invalid_argument("listen", options.listen + " is not a loopback address: serving beyond this machine needs TLS "
                                                          "(--tls-cert, --tls-key; --tls-client-ca for client certificates)");
    // Local credentials accept loopback peers only, even if the address were reachable.
    creds = grpc::experimental::LocalServerCredentials(LOCAL_TCP);
  }
  if (!options.token_file.empty()) {
    auto tokens = read_tokens(options.token_file);
    if (!tokens.ok()) return tokens.error();
    spdlog::info("bearer tokens required ({} configured)", tokens.value().size());
    configured_tokens() = std::make_shared<const std::vector<TokenEntry>>(std::move(tokens).value());
    creds->SetAuthMetadataProcessor(std::make_shared<TokenCheck>(configured_tokens()));
  }
  return creds;
}

grpc::Status require_role(const grpc::CallbackServerContext* ctx, Role needed) {
  const auto tokens = configured_tokens();
  if (!tokens) return grpc::Status::OK;  // no tokens: loopback or client certificates decide who connects
  const auto& metadata = ctx->client_metadata();
  const auto found = metadata.find(kAuthorization);
  const TokenEntry* entry =
      found == metadata.end() ? nullptr : entry_of(*tokens, std::string(found->second.data(), found->second.size()));
  if (!entry) return {grpc::StatusCode::UNAUTHENTICATED, "a known bearer token is required"};
  if (static_cast<int>(entry->role) >= static_cast<int>(needed)) return grpc::Status::OK;
  return {grpc::StatusCode::PERMISSION_DENIED,
          std::string("this call needs the ") + to_string(needed) + " role; the token has " + to_string(entry->role)};
}

}  // namespace gk::server
