#include "server/audit_handoff.h"

#include "engine/audits/audit_request.h"
#include "server/distributed_audit/audit_work_dir.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <cctype>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <set>
#include <thread>

extern char** environ;

namespace gk::server {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Job ids are the daemon's own ("audit-<epoch>-<n>"); anything else is kept out of the path.
std::string safe_name(const std::string& id) {
  std::string out;
  for (char c : id) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out.empty() ? "job" : out;
}

std::string log_tail(const std::string& path) {
  const std::string text = read_whole(path);
  return text.size() > 2000 ? "..." + text.substr(text.size() - 2000) : text;
}

// Ends the driver's process group: TERM, then KILL if it is still there after a grace period.
int stop_group(pid_t pid) {
  ::kill(-pid, SIGTERM);
  int status = 0;
  const auto give_up = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < give_up) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(-pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return status;
}

Result<engine::AuditResult> hand_off(const AuditHandoffOptions& config, const std::string& job_id, const engine::SceneRecord& snapshot,
                                     const std::vector<engine::AuditObject>& objects, const engine::AuditOptions& options) {
  auto failed = [&](const std::string& why) { return Error{ErrorCode::kInternal, "audit driver", why}; };
  const std::string work = config.data_dir + "/audit-work/" + safe_name(job_id);
  std::error_code ec;
  fs::create_directories(work, ec);
  if (ec) return failed("cannot create " + work + ": " + ec.message());
  // The plan: the same broad phase the driver runs (its tiles, their pairs), for the progress.
  engine::AuditOptions plan = options;
  plan.broad_phase_only = true;
  plan.on_progress = {};
  plan.on_clash = {};
  plan.on_tile_done = {};
  auto planned = engine::audit_scene(objects, plan);
  if (!planned.ok()) return planned.error();
  engine::AuditResult result = std::move(planned).value();
  // The snapshot and options as the driver will read them, and the fingerprint it will give its tiles.
  const std::string job_path = work + "/job.json";
  if (!write_whole(job_path, job_file_text(snapshot, options))) return failed("cannot write " + job_path);
  auto job = read_job_file(job_path);
  if (!job.ok()) return job.error();
  auto checked = engine::checked_audit_options(job.value().options, 1);
  if (!checked.ok()) return checked.error();
  const std::string print = audit_fingerprint(job.value().scene, checked.value());

  const std::string log_path = work + "/driver.log";
  const std::string command = config.command + " --data-dir " + quoted(config.data_dir) + " --job " + quoted(job_path) +
                              " --work-dir " + quoted(work) + " --out " + quoted(work + "/report.json");
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, 1, 2);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);  // its own group: a stop ends every process of it
  posix_spawnattr_setpgroup(&attributes, 0);
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, "/bin/sh", &files, &attributes, const_cast<char* const*>(argv), environ);
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) return failed("cannot start '" + config.command + "': " + std::strerror(spawned));
  spdlog::info("audit {}: driver started ({}), work directory {}", job_id, command, work);

  std::set<std::size_t> taken(options.skip_tiles.begin(), options.skip_tiles.end());
  engine::AuditProgress progress;
  for (std::size_t t = 0; t < result.tile_pairs.size(); ++t) {
    if (result.tile_pairs[t] == 0) continue;
    ++progress.tiles_total;
    progress.pairs_total += result.tile_pairs[t];
    if (taken.count(t)) {
      ++progress.tiles_done;
      progress.pairs_done += result.tile_pairs[t];
    }
  }
  result.clashes.clear();
  const auto t0 = Clock::now();
  std::string bad_tile;
  // Reads every tile the driver has finished since the last look.
  auto take_new_tiles = [&] {
    for (std::size_t t = 0; t < result.tile_pairs.size(); ++t) {
      if (result.tile_pairs[t] == 0 || taken.count(t) || !fs::exists(tile_path(work, t))) continue;
      auto tile = read_tile_file(tile_path(work, t), print, t);
      if (!tile.ok()) {
        bad_tile = tile.error().to_string();
        return;
      }
      taken.insert(t);
      for (const engine::PairClash& c : tile.value()) {
        if (c.b >= objects.size() || c.a >= c.b) {
          bad_tile = tile_path(work, t) + " names objects this snapshot does not have";
          return;
        }
        if (options.on_clash) options.on_clash(c);
      }
      if (options.on_tile_done) options.on_tile_done(t, tile.value());
      result.clashes.insert(result.clashes.end(), tile.value().begin(), tile.value().end());
      ++progress.tiles_done;
      progress.pairs_done += result.tile_pairs[t];
      progress.clashes = result.clashes.size();
      progress.elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
      if (options.on_progress) options.on_progress(progress);
    }
  };
  if (options.on_progress) options.on_progress(progress);
  int status = 0;
  bool ended = false, cancelled = false;
  while (!ended) {
    if (options.cancel && options.cancel->load()) {
      status = stop_group(pid);
      cancelled = true;
      ended = true;
    } else if (::waitpid(pid, &status, WNOHANG) == pid) {
      ended = true;
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    take_new_tiles();
    if (!bad_tile.empty()) {
      if (!ended) stop_group(pid);
      return failed(bad_tile);
    }
  }
  result.pairs_done = progress.pairs_done;
  result.cancelled = cancelled;
  engine::sort_in_pair_order(result.clashes);
  if (cancelled) return result;  // the tiles it finished (the work directory stays, for a resume)
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return failed("'" + config.command + "' ended with status " + std::to_string(status) + "; its log (" + log_path + "):\n" + log_tail(log_path));
  if (progress.tiles_done != progress.tiles_total)
    return failed("the driver ended with " + std::to_string(progress.tiles_total - progress.tiles_done) + " tiles missing; its log (" +
                  log_path + "):\n" + log_tail(log_path));
  fs::remove_all(work, ec);
  return result;
}

}  // namespace

engine::AuditRunner make_audit_handoff(AuditHandoffOptions options) {
  return [options](const std::string& job_id, const engine::SceneRecord& snapshot, const std::vector<engine::AuditObject>& objects,
                   const engine::AuditOptions& audit) { return hand_off(options, job_id, snapshot, objects, audit); };
}

}  // namespace gk::server
