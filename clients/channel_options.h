// How a client reaches gatekeeperd: the address, TLS (the CA that signed the server's
// certificate; a client certificate for mutual TLS) and a bearer token — the options every
// command-line client takes, matching the daemon's --tls-* and --token-file.
//
// Without --tls-ca the channel uses gRPC's local credentials (loopback only), which carry a token;
// a plain insecure channel would not send one.
#pragma once

#include <CLI/CLI.hpp>
#include <grpcpp/grpcpp.h>
#include <grpcpp/security/credentials.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

namespace gk::clients {

struct ChannelOptions {
  std::string address = "127.0.0.1:50051";
  std::string tls_ca;      // PEM: trust this CA for the server's certificate (turns TLS on)
  std::string tls_cert;    // PEM client certificate (mutual TLS)
  std::string tls_key;     // PEM key of tls_cert
  std::string server_name; // the name the server's certificate was issued for, if not the address's host
  std::string token_file;  // a file holding the bearer token (kept out of the process list)

  void add_to(CLI::App& app) {
    app.add_option("--address", address, "gatekeeperd's host:port");
    app.add_option("--tls-ca", tls_ca, "PEM CA of the server's certificate: connect with TLS");
    app.add_option("--tls-cert", tls_cert, "PEM client certificate (mutual TLS)");
    app.add_option("--tls-key", tls_key, "PEM key of --tls-cert");
    app.add_option("--tls-server-name", server_name, "the name on the server's certificate, if not the address's host");
    app.add_option("--token-file", token_file, "a file holding the bearer token");
  }

  // Throws std::runtime_error naming the option when a file cannot be read.
  std::shared_ptr<grpc::Channel> open(grpc::ChannelArguments args = {}) const {
    std::shared_ptr<grpc::ChannelCredentials> creds;
    if (!tls_ca.empty()) {
      grpc::SslCredentialsOptions ssl;
      ssl.pem_root_certs = read(tls_ca, "--tls-ca");
      if (!tls_cert.empty()) ssl.pem_cert_chain = read(tls_cert, "--tls-cert");
      if (!tls_key.empty()) ssl.pem_private_key = read(tls_key, "--tls-key");
      creds = grpc::SslCredentials(ssl);
      if (!server_name.empty()) args.SetSslTargetNameOverride(server_name);
    } else {
      creds = grpc::experimental::LocalCredentials(LOCAL_TCP);
    }
    if (!token_file.empty()) {
      std::string token = read(token_file, "--token-file");
      while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' ')) token.pop_back();
      creds = grpc::CompositeChannelCredentials(creds, grpc::AccessTokenCredentials(token));
    }
    return grpc::CreateCustomChannel(address, creds, args);
  }

 private:
  static std::string read(const std::string& path, const char* option) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(std::string(option) + ": cannot read " + path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
};

}  // namespace gk::clients
