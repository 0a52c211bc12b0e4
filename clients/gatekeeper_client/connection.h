// How a C++ program reaches gatekeeperd: the address, TLS (the CA that signed the server's
// certificate; a client certificate for mutual TLS) and a bearer token, matching the daemon's
// --tls-* and --token-file. Without a CA the channel uses gRPC's local credentials (loopback
// only), which carry a token; a plain insecure channel would not send one.
#pragma once

#include "gatekeeper/v1/gatekeeper.grpc.pb.h"

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

namespace gk::client {

struct ConnectionOptions {
  std::string address = "127.0.0.1:50051";
  std::string tls_ca;       // PEM: trust this CA for the server's certificate (turns TLS on)
  std::string tls_cert;     // PEM client certificate (mutual TLS)
  std::string tls_key;      // PEM key of tls_cert
  std::string server_name;  // the name the server's certificate was issued for, if not the address's host
  std::string token_file;   // a file holding the bearer token (kept out of the process list)
};

// The channel; throws std::runtime_error naming the option when a file cannot be read.
std::shared_ptr<grpc::Channel> open_channel(const ConnectionOptions& options, grpc::ChannelArguments args = {});

// A stub on a channel that connected within wait_s seconds (std::runtime_error otherwise).
std::unique_ptr<::gatekeeper::v1::Gatekeeper::Stub> connect(const ConnectionOptions& options, double wait_s = 10.0,
                                                            grpc::ChannelArguments args = {});

}  // namespace gk::client
