#include "clients/gatekeeper_client/connection.h"

#include <grpcpp/security/credentials.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace gk::client {
namespace {

std::string read(const std::string& path, const char* option) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(std::string(option) + ": cannot read " + path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

std::shared_ptr<grpc::Channel> open_channel(const ConnectionOptions& options, grpc::ChannelArguments args) {
  std::shared_ptr<grpc::ChannelCredentials> creds;
  if (!options.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = read(options.tls_ca, "--tls-ca");
    if (!options.tls_cert.empty()) ssl.pem_cert_chain = read(options.tls_cert, "--tls-cert");
    if (!options.tls_key.empty()) ssl.pem_private_key = read(options.tls_key, "--tls-key");
    creds = grpc::SslCredentials(ssl);
    if (!options.server_name.empty()) args.SetSslTargetNameOverride(options.server_name);
  } else {
    creds = grpc::experimental::LocalCredentials(LOCAL_TCP);
  }
  if (!options.token_file.empty()) {
    std::string token = read(options.token_file, "--token-file");
    while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' ')) token.pop_back();
    creds = grpc::CompositeChannelCredentials(creds, grpc::AccessTokenCredentials(token));
  }
  return grpc::CreateCustomChannel(options.address, creds, args);
}

std::unique_ptr<::gatekeeper::v1::Gatekeeper::Stub> connect(const ConnectionOptions& options, double wait_s,
                                                            grpc::ChannelArguments args) {
  auto channel = open_channel(options, std::move(args));
  const auto deadline = std::chrono::system_clock::now() + std::chrono::milliseconds(static_cast<long long>(wait_s * 1000.0));
  if (!channel->WaitForConnected(deadline)) throw std::runtime_error("cannot connect to " + options.address);
  return ::gatekeeper::v1::Gatekeeper::NewStub(channel);
}

}  // namespace gk::client
