// gatekeeperd: the physics gatekeeper's gRPC daemon.
//
//   gatekeeperd [--listen 127.0.0.1:50051] [--data-dir DIR] [--config FILE.toml] [--workers N]
//               [--queue N] [--audit-jobs N] [--port-file FILE] [--log-level info] [--log-format text|json]
//               [--log-file FILE] [--log-calls true|false] [--metrics-listen 127.0.0.1:9464 [--metrics-port-file FILE]]
//               [--tls-cert PEM --tls-key PEM [--tls-client-ca PEM]] [--token-file FILE]
//               [--part-memory-gb 8] [--audits-in-memory 16] [--cad-check-seconds 120] [--cad-check-memory-gb 8]
//
// Without TLS it serves loopback addresses only (see server/access_control.h). Everything it
// writes is private to its user: the data directory 0700, files 0600 (umask 077). CAD files are
// first read in a child process, this program run as `gatekeeperd --check-cad ...`
// (engine/parts/cad_sandbox.h): a reader that crashes on a malformed file takes only the child down.
//
// Logs go to standard error (or --log-file) as text or one JSON object per line, with one line per
// answered call: its request id (the client's x-request-id or a new one, echoed back), method,
// status, latency, and the verdict and deciding stage where the answer has them. With
// --metrics-listen, GET /metrics serves Prometheus text on that loopback address.
//
// Starts with the embedded default P4 machine model; health (grpc.health.v1) and reflection
// (v1alpha) are served; SIGTERM or SIGINT shut it down gracefully (health NOT_SERVING, in-flight
// calls get --drain-seconds to finish, workers join, storage closes).
#include "engine/gatekeeper_engine.h"
#include "engine/parts/cad_sandbox.h"
#include "server/access_control.h"
#include "server/audit_handoff.h"
#include "server/audit_archive.h"
#include "server/audit_checkpoint_store.h"
#include "server/clash_status_store.h"
#include "server/gatekeeper_service.h"
#include "server/metrics_endpoint.h"
#include "server/request_log.h"

#include <CLI/CLI.hpp>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>
#include <toml++/toml.h>

#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <pthread.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>

namespace {

struct Config {
  std::string listen = "127.0.0.1:50051";
  std::string data_dir = "gatekeeper-data";
  std::string port_file;
  std::string log_level = "info";
  std::string log_format = "text";
  std::string log_file;
  bool log_calls = true;
  std::string metrics_listen;  // empty: no /metrics
  std::string metrics_port_file;
  int workers = 2;
  int queue = 64;
  int audit_jobs = 1;
  int max_uploads = 64;
  double upload_idle_seconds = 60.0;
  int drain_seconds = 5;
  int cad_check_seconds = 120;
  double cad_check_memory_gb = 8.0;
  double part_memory_gb = 8.0;
  int audits_in_memory = 16;
  std::string audit_driver;              // empty: every audit runs in this process
  double audit_driver_min_triangles = 1e7;
  int validation_workers = 2;
  int part_validation_workers = 1;
  int upload_workers = 1;
  int scene_workers = 2;
  int record_workers = 1;
  gk::server::AccessOptions access;
};

// Values from a TOML config file; flags given on the command line win.
bool apply_config_file(const std::string& path, Config& c, const CLI::App& app) {
  try {
    const toml::table t = toml::parse_file(path);
    if (app.count("--listen") == 0) c.listen = t["listen"].value_or(c.listen);
    if (app.count("--data-dir") == 0) c.data_dir = t["data_dir"].value_or(c.data_dir);
    if (app.count("--workers") == 0) c.workers = t["workers"].value_or(c.workers);
    if (app.count("--queue") == 0) c.queue = t["queue"].value_or(c.queue);
    if (app.count("--audit-jobs") == 0) c.audit_jobs = t["audit_jobs"].value_or(c.audit_jobs);
    if (app.count("--log-level") == 0) c.log_level = t["log_level"].value_or(c.log_level);
    if (app.count("--log-format") == 0) c.log_format = t["log_format"].value_or(c.log_format);
    if (app.count("--log-file") == 0) c.log_file = t["log_file"].value_or(c.log_file);
    if (app.count("--log-calls") == 0) c.log_calls = t["log_calls"].value_or(c.log_calls);
    if (app.count("--metrics-listen") == 0) c.metrics_listen = t["metrics_listen"].value_or(c.metrics_listen);
    if (app.count("--part-memory-gb") == 0) c.part_memory_gb = t["part_memory_gb"].value_or(c.part_memory_gb);
    if (app.count("--audit-driver") == 0) c.audit_driver = t["audit_driver"].value_or(c.audit_driver);
    if (app.count("--audit-driver-min-triangles") == 0)
      c.audit_driver_min_triangles = t["audit_driver_min_triangles"].value_or(c.audit_driver_min_triangles);
    if (app.count("--tls-cert") == 0) c.access.tls_cert_file = t["tls_cert"].value_or(c.access.tls_cert_file);
    if (app.count("--tls-key") == 0) c.access.tls_key_file = t["tls_key"].value_or(c.access.tls_key_file);
    if (app.count("--tls-client-ca") == 0) c.access.tls_client_ca = t["tls_client_ca"].value_or(c.access.tls_client_ca);
    if (app.count("--token-file") == 0) c.access.token_file = t["token_file"].value_or(c.access.token_file);
    return true;
  } catch (const toml::parse_error& e) {
    spdlog::error("config {}: {}", path, std::string(e.description()));
    return false;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--check-cad") return gk::engine::run_cad_check(argc, argv);
  Config config;
  std::string config_file;
  CLI::App app{"gatekeeperd: decides, before a machine moves, whether the move is physically possible"};
  app.add_option("--listen", config.listen, "address:port to listen on (port 0: any free port)");
  app.add_option("--data-dir", config.data_dir, "where uploaded parts and their records are stored");
  app.add_option("--config", config_file,
                 "a TOML file with listen, data_dir, workers, queue, audit_jobs, log_level, log_format, log_file, "
                 "log_calls, metrics_listen, part_memory_gb, audit_driver, audit_driver_min_triangles, tls_cert, tls_key, "
                 "tls_client_ca, token_file");
  app.add_option("--workers", config.workers, "threads for clearance queries")->check(CLI::Range(1, 64));
  app.add_option("--validation-workers", config.validation_workers, "threads validating steps of parametric parts")
      ->check(CLI::Range(1, 64));
  app.add_option("--part-validation-workers", config.part_validation_workers,
                 "threads validating steps of uploaded (mesh or CAD) parts, apart so that they never queue the others")
      ->check(CLI::Range(1, 64));
  app.add_option("--upload-workers", config.upload_workers, "threads reading finished uploads")->check(CLI::Range(1, 64));
  app.add_option("--scene-workers", config.scene_workers, "threads placing and moving scene objects (their contacts)")
      ->check(CLI::Range(1, 64));
  app.add_option("--record-workers", config.record_workers,
                 "threads writing scene batches and machine models and reading audit reports")
      ->check(CLI::Range(1, 64));
  app.add_option("--queue", config.queue, "queued jobs beyond which requests get RESOURCE_EXHAUSTED")->check(CLI::Range(1, 100000));
  app.add_option("--audit-jobs", config.audit_jobs, "audits run at once, on their own threads (a running audit never delays queries)")
      ->check(CLI::Range(1, 16));
  app.add_option("--audit-driver", config.audit_driver,
                 "a command that runs an audit over many processes or machines, given --data-dir, --job, --work-dir and --out "
                 "(e.g. \"mpiexec -n 8 --hostfile hosts gatekeeper-audit\"); audits of large scenes are handed to it");
  app.add_option("--audit-driver-min-triangles", config.audit_driver_min_triangles,
                 "scenes with at least this many triangles (counted per object) are audited by --audit-driver")
      ->check(CLI::Range(0.0, 1e15));
  app.add_option("--max-uploads", config.max_uploads, "upload streams open at once (each holds a file)")->check(CLI::Range(1, 10000));
  app.add_option("--upload-idle-seconds", config.upload_idle_seconds, "an upload stream silent this long is cancelled")
      ->check(CLI::Range(0.1, 86400.0));
  app.add_option("--port-file", config.port_file, "write the bound port to this file once serving");
  app.add_option("--drain-seconds", config.drain_seconds, "on SIGTERM, how long in-flight calls may finish")
      ->check(CLI::Range(0, 600));
  app.add_option("--log-level", config.log_level, "trace, debug, info, warn, error");
  app.add_option("--log-format", config.log_format, "text, or json: one JSON object per line");
  app.add_option("--log-file", config.log_file, "append the log to this file instead of standard error");
  app.add_option("--log-calls", config.log_calls, "one log line per answered call (info; calls the daemon failed: error)");
  app.add_option("--metrics-listen", config.metrics_listen,
                 "serve GET /metrics (Prometheus text) on this loopback host:port (port 0: any free port)");
  app.add_option("--metrics-port-file", config.metrics_port_file, "write the bound /metrics port to this file");
  app.add_option("--tls-cert", config.access.tls_cert_file, "PEM certificate chain: serve TLS (needed beyond loopback)");
  app.add_option("--tls-key", config.access.tls_key_file, "PEM private key of --tls-cert (mode 0600)");
  app.add_option("--tls-client-ca", config.access.tls_client_ca, "PEM CA: require client certificates it signed (mutual TLS)");
  app.add_option("--token-file", config.access.token_file,
                 "lines \"<read|write|admin> <token>\" (mode 0600): every call needs \"authorization: Bearer <token>\"");
  app.add_option("--part-memory-gb", config.part_memory_gb,
                 "memory for loaded parts (meshes and trees, estimated); beyond it the least recently used are read again from disk when needed")
      ->check(CLI::Range(0.0001, 4096.0));
  app.add_option("--audits-in-memory", config.audits_in_memory,
                 "ended audits kept in memory; older ones are read from the database when asked for")
      ->check(CLI::Range(1, 100000));
  app.add_option("--cad-check-seconds", config.cad_check_seconds, "longest a CAD file may take to read and tessellate")
      ->check(CLI::Range(1, 86400));
  app.add_option("--cad-check-memory-gb", config.cad_check_memory_gb, "most memory reading one CAD file may take")
      ->check(CLI::Range(0.5, 1024.0));
  CLI11_PARSE(app, argc, argv);
  if (!config_file.empty() && !apply_config_file(config_file, config, app)) return 2;
  ::umask(077);
  {
    // Every connection and part file takes a descriptor: the soft limit (often 1024) up to the hard one.
    rlimit files{};
    if (::getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur < files.rlim_max) {
      files.rlim_cur = files.rlim_max;
      ::setrlimit(RLIMIT_NOFILE, &files);
    }
  }
  {
    // The CAD readers run first in a child: this very program, found by its own path.
    std::error_code ec;
    const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (ec) {
      spdlog::error("cannot find this program's path (/proc/self/exe) to read CAD files in a child: {}", ec.message());
      return 1;
    }
    gk::engine::CadSandbox sandbox;
    sandbox.executable = self.string();
    sandbox.timeout = std::chrono::seconds(config.cad_check_seconds);
    sandbox.memory_bytes = static_cast<std::uint64_t>(config.cad_check_memory_gb * 1073741824.0);
    gk::engine::set_cad_sandbox(sandbox);
  }
  {
    gk::server::LogOptions log;
    const auto format = gk::server::log_format_named(config.log_format);
    if (!format) {
      spdlog::error("--log-format: \"{}\" is not text or json", config.log_format);
      return 2;
    }
    log.format = *format;
    log.level = config.log_level;
    log.file = config.log_file;
    log.call_lines = config.log_calls;
    if (auto failed = gk::server::configure_logging(log)) {
      spdlog::error("{}", *failed);
      return 2;
    }
  }

  // Block the shutdown signals in every thread; the main thread waits for them below.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  config.access.listen = config.listen;
  auto credentials = gk::server::server_credentials(config.access);
  if (!credentials.ok()) {
    spdlog::error("{}", credentials.error().to_string());
    return 2;
  }
  // Parts, scenes and reports are the customer's: nothing this daemon writes is readable by others
  // (umask set before the log file is opened).
  ::mkdir(config.data_dir.c_str(), 0700);
  ::chmod(config.data_dir.c_str(), 0700);
  {
    // What an earlier run (or another tool) left in it is closed too; links are not followed.
    std::error_code ec;
    for (auto it = std::filesystem::recursive_directory_iterator(config.data_dir, ec);
         !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
      if (it->is_symlink(ec)) continue;
      std::filesystem::permissions(it->path(), std::filesystem::perms::group_all | std::filesystem::perms::others_all,
                                   std::filesystem::perm_options::remove | std::filesystem::perm_options::nofollow, ec);
    }
  }

  // One daemon per data directory: a second one would resume the first one's audits and write
  // the same databases. The lock goes with the process (also on kill -9).
  const std::string lock_path = config.data_dir + "/gatekeeperd.lock";
  const int lock_fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (lock_fd < 0 || ::flock(lock_fd, LOCK_EX | LOCK_NB) != 0) {
    spdlog::error("data_dir: another gatekeeperd is using {} (or {} cannot be locked)", config.data_dir, lock_path);
    return 1;
  }

  auto store = gk::engine::PartStore::open(config.data_dir);
  if (!store.ok()) {
    spdlog::error("{}", store.error().to_string());
    return 1;
  }
  gk::engine::PartRegistry parts(*store.value(), config.data_dir + "/bvh-cache",
                                 static_cast<std::size_t>(config.part_memory_gb * 1073741824.0));
  auto machines = gk::engine::MachineRegistry::create(config.data_dir + "/machines");
  if (!machines.ok()) {
    spdlog::error("default machine model: {}", machines.error().to_string());
    return 1;
  }
  gk::server::ServiceOptions options;
  options.workers = config.workers;
  options.max_queued = static_cast<std::size_t>(config.queue);
  options.validation_workers = config.validation_workers;
  options.part_validation_workers = config.part_validation_workers;
  options.upload_workers = config.upload_workers;
  options.scene_workers = config.scene_workers;
  options.record_workers = config.record_workers;
  options.max_open_uploads = static_cast<std::size_t>(config.max_uploads);
  options.upload_idle_limit = std::chrono::milliseconds(static_cast<long long>(config.upload_idle_seconds * 1000.0));
  auto scenes = gk::engine::SceneStore::open(config.data_dir);
  if (!scenes.ok()) {
    spdlog::error("{}", scenes.error().to_string());
    return 1;
  }
  auto archive = gk::server::AuditArchive::open(config.data_dir);
  if (!archive.ok()) {
    spdlog::error("{}", archive.error().to_string());
    return 1;
  }
  auto checkpoints = gk::server::AuditCheckpointStore::open(config.data_dir);
  if (!checkpoints.ok()) {
    spdlog::error("{}", checkpoints.error().to_string());
    return 1;
  }
  auto clash_statuses = gk::server::ClashStatusStore::open(config.data_dir);
  if (!clash_statuses.ok()) {
    spdlog::error("{}", clash_statuses.error().to_string());
    return 1;
  }
  gk::engine::EngineOptions engine_options;
  engine_options.audit_threads = config.workers;
  engine_options.audits.concurrent = config.audit_jobs;
  engine_options.audits.ended_in_memory = static_cast<std::size_t>(config.audits_in_memory);
  if (!config.audit_driver.empty()) {
    engine_options.audits.large_audits = gk::server::make_audit_handoff({config.audit_driver, config.data_dir});
    engine_options.audits.large_audit_min_triangles = static_cast<std::size_t>(config.audit_driver_min_triangles);
    spdlog::info("audits of {} triangles or more are handed to: {}", engine_options.audits.large_audit_min_triangles,
                 config.audit_driver);
  }
  gk::engine::Engine engine(*machines.value(), parts, *scenes.value(), archive.value().get(), engine_options,
                            checkpoints.value().get(), clash_statuses.value().get());
  gk::server::GatekeeperService service(engine, options);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(config.listen, credentials.value(), &port);
  builder.RegisterService(&service);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    spdlog::error("cannot listen on {}", config.listen);
    return 1;
  }
  std::unique_ptr<gk::server::MetricsEndpoint> metrics;
  if (!config.metrics_listen.empty()) {
    metrics = std::make_unique<gk::server::MetricsEndpoint>([&service] { return gk::server::prometheus_text(service.metrics()); });
    auto bound = metrics->start(config.metrics_listen);
    if (!bound.ok()) {
      spdlog::error("{}", bound.error().to_string());
      server->Shutdown();
      service.stop_work();
      return 2;
    }
    spdlog::info("metrics on http://{}/metrics", config.metrics_listen.substr(0, config.metrics_listen.rfind(':') + 1) +
                                                     std::to_string(bound.value()));
    if (!config.metrics_port_file.empty()) {
      std::ofstream(config.metrics_port_file + ".tmp") << bound.value() << "\n";
      std::rename((config.metrics_port_file + ".tmp").c_str(), config.metrics_port_file.c_str());
    }
  }
  // Audits a stopped or killed daemon left running resume from their finished tiles.
  if (const std::size_t resumed = engine.resume_audits(); resumed > 0) spdlog::info("{} unfinished audits resumed", resumed);
  server->GetHealthCheckService()->SetServingStatus(true);
  spdlog::info("gatekeeperd serving on port {} (data in {}, machine {})", port, config.data_dir,
               gk::engine::MachineRegistry::kDefaultMachine);
  if (!config.port_file.empty()) {
    std::ofstream(config.port_file + ".tmp") << port << "\n";
    std::rename((config.port_file + ".tmp").c_str(), config.port_file.c_str());
  }

  int received = 0;
  sigwait(&signals, &received);
  spdlog::info("signal {}: draining", received);
  server->GetHealthCheckService()->SetServingStatus(false);
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(config.drain_seconds));
  metrics.reset();
  service.stop_work();
  spdlog::info("stopped");
  return 0;
}
