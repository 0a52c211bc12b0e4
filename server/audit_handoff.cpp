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
#include <cerrno>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
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

bool group_alive(pid_t group) { return ::kill(-group, 0) == 0 || errno == EPERM; }

// Ends the driver's process group: TERM (mpiexec passes it on to its ranks), then KILL to whatever
// of the group is left after a grace period; reaps the leader. Returns its wait status.
int stop_group(pid_t pid, bool reaped, int status) {
  ::kill(-pid, SIGTERM);
  const auto give_up = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < give_up) {
    if (!reaped && ::waitpid(pid, &status, WNOHANG) == pid) reaped = true;
    if (reaped && !group_alive(pid)) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(-pid, SIGKILL);
  if (!reaped) ::waitpid(pid, &status, 0);
  return status;
}

// Every process whose command line names this work directory (a driver, mpiexec and its ranks,
// which Open MPI puts in process groups of their own), but this one.
std::vector<pid_t> processes_naming(const std::string& work) {
  std::vector<pid_t> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", fs::directory_options::skip_permission_denied, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || !std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; })) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(name));
    if (pid == ::getpid()) continue;
    std::ifstream cmd_file(entry.path() / "cmdline");
    const std::string cmdline((std::istreambuf_iterator<char>(cmd_file)), std::istreambuf_iterator<char>());
    if (cmdline.find(work) != std::string::npos) out.push_back(pid);
  }
  return out;
}

// A driver of this work directory left running by a daemon that was killed: TERM to each of its
// processes, KILL to those left after a grace period, before another driver starts there.
void end_leftover_driver(const std::string& work) {
  std::vector<pid_t> left = processes_naming(work);
  if (left.empty()) return;
  spdlog::warn("ending {} leftover audit driver process(es) of {}", left.size(), work);
  for (pid_t pid : left) ::kill(pid, SIGTERM);
  const auto give_up = Clock::now() + std::chrono::seconds(5);
  while (!left.empty() && Clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    left = processes_naming(work);
  }
  for (pid_t pid : left) ::kill(pid, SIGKILL);
}

std::string exit_text(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "signal " + std::to_string(WTERMSIG(status));
  return "status " + std::to_string(status);
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

  end_leftover_driver(work);
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
  // As the daemon's own audit counts them: tiles of the floor plan, all done once their broad
  // phase is (the driver ran it); pairs done as their tiles come back.
  progress.tiles_total = progress.tiles_done = result.tiles;
  std::size_t tiles_expected = 0, tiles_taken = 0;
  for (std::size_t t = 0; t < result.tile_pairs.size(); ++t) {
    if (result.tile_pairs[t] == 0) continue;
    ++tiles_expected;
    progress.pairs_total += result.tile_pairs[t];
    if (taken.count(t)) {
      ++tiles_taken;
      progress.pairs_done += result.tile_pairs[t];
    }
  }
  std::set<std::pair<std::uint32_t, std::uint32_t>> pairs_seen;
  result.clashes.clear();
  const auto t0 = Clock::now();
  std::string bad_tile;
  // Reads every tile the driver has finished since the last look.
  // A clash the driver reports must be one the plan can hold: objects in range, each pair once,
  // finite numbers. (The driver is trusted like the daemon for what it leaves out: a pair it does
  // not report is not recomputed here.)
  auto plausible = [&](const engine::PairClash& c) {
    return c.a < c.b && c.b < objects.size() && pairs_seen.insert({c.a, c.b}).second && std::isfinite(c.distance_mm) &&
           c.distance_mm >= 0.0 && c.point_a.allFinite() && c.point_b.allFinite();
  };
  auto take_new_tiles = [&] {
    for (std::size_t t = 0; t < result.tile_pairs.size(); ++t) {
      std::error_code missing;
      if (result.tile_pairs[t] == 0 || taken.count(t) || !fs::exists(tile_path(work, t), missing)) continue;
      auto tile = read_tile_file(tile_path(work, t), print, t);
      if (!tile.ok()) {
        bad_tile = tile.error().to_string();
        return;
      }
      taken.insert(t);
      for (const engine::PairClash& c : tile.value())
        if (!plausible(c)) {
          bad_tile = tile_path(work, t) + " holds a clash this audit cannot have (objects out of range, a pair twice, or a number not finite)";
          return;
        }
      for (const engine::PairClash& c : tile.value())
        if (options.on_clash) options.on_clash(c);
      if (options.on_tile_done) options.on_tile_done(t, tile.value());
      result.clashes.insert(result.clashes.end(), tile.value().begin(), tile.value().end());
      ++tiles_taken;
      progress.pairs_done += result.tile_pairs[t];
      progress.clashes = result.clashes.size();
      progress.elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
      if (options.on_progress) options.on_progress(progress);
    }
  };
  if (options.on_progress) options.on_progress(progress);
  int status = 0;
  bool reaped = false, cancelled = false;
  std::optional<Clock::time_point> all_in;  // when the last tile came back
  // Whatever happens below (a bad tile, an exception), the driver does not outlive this call.
  struct Guard {
    pid_t pid;
    bool* reaped;
    int* status;
    ~Guard() {
      if (!*reaped) *status = stop_group(pid, false, *status);
      *reaped = true;
    }
  } guard{pid, &reaped, &status};
  while (!reaped) {
    if (options.cancel && options.cancel->load()) {
      status = stop_group(pid, false, status);
      reaped = cancelled = true;
    } else if (::waitpid(pid, &status, WNOHANG) == pid) {
      reaped = true;
      if (group_alive(pid)) status = stop_group(pid, true, status);  // the leader is gone: none of its group stays
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    take_new_tiles();
    if (!bad_tile.empty()) return failed(bad_tile);  // the guard ends the driver
    if (tiles_taken == tiles_expected && !reaped) {
      // Every tile is in: the driver's own merge is not needed here. It gets a while to end.
      if (!all_in) all_in = Clock::now();
      if (Clock::now() - *all_in > std::chrono::seconds(30)) {
        spdlog::warn("audit {}: the driver wrote every tile but did not end in 30 s; it is stopped", job_id);
        status = stop_group(pid, false, status);
        reaped = true;
        status = 0;
      }
    }
  }
  result.pairs_done = progress.pairs_done;
  result.cancelled = cancelled;
  engine::sort_in_pair_order(result.clashes);
  if (cancelled) return result;  // the tiles it finished (the work directory stays, for a resume)
  if (tiles_taken == tiles_expected && status == 0) {
    fs::remove_all(work, ec);
    return result;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return failed("'" + config.command + "' ended with " + exit_text(status) + "; its log (" + log_path + "):\n" + log_tail(log_path));
  return failed("the driver ended with " + std::to_string(tiles_expected - tiles_taken) + " tiles missing; its log (" + log_path +
                "):\n" + log_tail(log_path));
}

}  // namespace

engine::AuditRunner make_audit_handoff(AuditHandoffOptions options) {
  return [options](const std::string& job_id, const engine::SceneRecord& snapshot, const std::vector<engine::AuditObject>& objects,
                   const engine::AuditOptions& audit) { return hand_off(options, job_id, snapshot, objects, audit); };
}

}  // namespace gk::server
