// The connection flags every command-line client takes (--address, --tls-*, --token-file), over
// the client library's ConnectionOptions (clients/gatekeeper_client/connection.h).
#pragma once

#include "clients/gatekeeper_client/connection.h"

#include <CLI/CLI.hpp>

namespace gk::clients {

struct ChannelOptions : client::ConnectionOptions {
  void add_to(CLI::App& app) {
    app.add_option("--address", address, "gatekeeperd's host:port");
    app.add_option("--tls-ca", tls_ca, "PEM CA of the server's certificate: connect with TLS");
    app.add_option("--tls-cert", tls_cert, "PEM client certificate (mutual TLS)");
    app.add_option("--tls-key", tls_key, "PEM key of --tls-cert");
    app.add_option("--tls-server-name", server_name, "the name on the server's certificate, if not the address's host");
    app.add_option("--token-file", token_file, "a file holding the bearer token");
  }
  // Throws std::runtime_error naming the option when a file cannot be read.
  std::shared_ptr<grpc::Channel> open(grpc::ChannelArguments args = {}) const { return client::open_channel(*this, std::move(args)); }
};

}  // namespace gk::clients
