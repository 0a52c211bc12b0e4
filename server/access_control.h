// Who may call the daemon: transport security (TLS, mutual TLS, or loopback only) and bearer
// tokens with roles.
//
// - Without TLS the daemon listens on loopback addresses only (gRPC's local credentials refuse
//   any other peer), so an unconfigured daemon is never open to a shop network.
// - With --tls-cert/--tls-key it serves TLS; with --tls-client-ca also it requires a client
//   certificate signed by that CA (mutual TLS). Beyond loopback TLS needs client certificates or
//   tokens (TLS alone would let anybody call).
// - With --token-file every call must carry "authorization: Bearer <token>"; the token's role
//   decides what it may do. A call without a known token is UNAUTHENTICATED before any handler
//   runs; a handler needing a higher role answers PERMISSION_DENIED. Each call's own header
//   decides (one connection may carry the calls of several tokens).
#pragma once

#include "kernel/core/status.h"

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

namespace gk::server {

// Ordered: each role may do what the ones before it may.
enum class Role { kRead, kWrite, kAdmin };
const char* to_string(Role role);

struct AccessOptions {
  std::string listen;          // host:port
  std::string tls_cert_file;   // PEM server certificate chain
  std::string tls_key_file;    // PEM private key
  std::string tls_client_ca;   // PEM CA of accepted client certificates (mutual TLS)
  std::string token_file;      // lines "<read|write|admin> <token>"; '#' comments
};

// The credentials to listen with, token checking included; an error naming the option when the
// configuration is unsafe (a non-loopback address without TLS) or a file is unreadable or bad.
Result<std::shared_ptr<grpc::ServerCredentials>> server_credentials(const AccessOptions& options);

// OK when the caller's role (set by the token check) is at least `needed`, or when no tokens
// are configured (loopback or TLS alone decide who connects); else PERMISSION_DENIED.
grpc::Status require_role(const grpc::CallbackServerContext* ctx, Role needed);

// Whether "host:port" names a loopback host (127.0.0.0/8, ::1, localhost).
bool is_loopback_listen_address(const std::string& listen);

}  // namespace gk::server
