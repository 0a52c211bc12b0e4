#include "server/request_log.h"

#include <spdlog/details/log_msg.h>
#include <spdlog/formatter.h>
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>

namespace gk::server {
namespace {

constexpr const char* kCallLogger = "calls";
std::atomic<bool> g_call_lines{true};
std::atomic<LogFormat> g_format{LogFormat::kText};

// Length of the valid UTF-8 sequence starting at s[i], 0 when it is not one.
std::size_t utf8_length(const std::string& s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  std::size_t n = 0;
  unsigned min = 0;
  unsigned code = 0;
  if (c < 0x80) return 1;
  if ((c & 0xE0) == 0xC0) n = 2, code = c & 0x1F, min = 0x80;
  else if ((c & 0xF0) == 0xE0) n = 3, code = c & 0x0F, min = 0x800;
  else if ((c & 0xF8) == 0xF0) n = 4, code = c & 0x07, min = 0x10000;
  else return 0;
  if (i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
    code = (code << 6) | (byte(i + k) & 0x3F);
  }
  if (code < min || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return 0;
  return n;
}

// "2026-11-26T16:01:02.123456Z"
std::string utc_time(std::chrono::system_clock::time_point t) {
  const auto since = t.time_since_epoch();
  const std::time_t seconds = std::chrono::duration_cast<std::chrono::seconds>(since).count();
  const long micros = static_cast<long>(std::chrono::duration_cast<std::chrono::microseconds>(since).count() % 1000000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char out[96];
  std::snprintf(out, sizeof out, "%04d-%02d-%02dT%02d:%02d:%02d.%06ldZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, micros);
  return out;
}

// One JSON object per line. A call line's payload already is the object's fields ("k":v,...);
// every other message becomes the "msg" string.
class JsonLineFormatter final : public spdlog::formatter {
 public:
  void format(const spdlog::details::log_msg& msg, spdlog::memory_buf_t& dest) override {
    const std::string payload(msg.payload.data(), msg.payload.size());
    const std::string logger(msg.logger_name.data(), msg.logger_name.size());
    const auto level = spdlog::level::to_string_view(msg.level);
    std::string line = "{\"time\":\"" + utc_time(msg.time) + "\",\"level\":\"" + std::string(level.data(), level.size()) +
                       "\",\"logger\":" + json_string(logger.empty() ? "gatekeeperd" : logger);
    if (logger == kCallLogger) line += "," + payload;
    else line += ",\"msg\":" + json_string(payload);
    line += "}\n";
    dest.append(line.data(), line.data() + line.size());
  }
  std::unique_ptr<spdlog::formatter> clone() const override { return std::make_unique<JsonLineFormatter>(); }
};

}  // namespace

std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
      ++i;
    } else if (c < 0x20 || c == 0x7F) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\u%04x", c);
      out += esc;
      ++i;
    } else if (const std::size_t n = utf8_length(text, i); n > 0) {
      out.append(text, i, n);
      i += n;
    } else {
      out += "\\ufffd";  // not UTF-8: the replacement character, never raw bytes
      ++i;
    }
  }
  return out + "\"";
}

std::optional<LogFormat> log_format_named(const std::string& name) {
  if (name == "text") return LogFormat::kText;
  if (name == "json") return LogFormat::kJson;
  return std::nullopt;
}

std::optional<std::string> configure_logging(const LogOptions& options) {
  const spdlog::level::level_enum level = spdlog::level::from_str(options.level);
  if (level == spdlog::level::off && options.level != "off")
    return "--log-level: \"" + options.level + "\" is not one of trace, debug, info, warn, error, critical, off";
  if (!options.file.empty()) {
    // The directory must exist (spdlog would create it): a mistyped path is an error, not a tree.
    const std::filesystem::path parent = std::filesystem::path(options.file).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
      return "--log-file: the directory " + parent.string() + " does not exist";
  }
  try {
    // One sink for both loggers: its lock keeps every line whole (two sinks on one file
    // interleaved the pieces of long lines), and its one formatter knows call lines by logger.
    spdlog::sink_ptr sink;
    if (options.file.empty()) sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
    else sink = std::make_shared<spdlog::sinks::basic_file_sink_mt>(options.file);
    if (options.format == LogFormat::kJson) sink->set_formatter(std::make_unique<JsonLineFormatter>());
    auto main_logger = std::make_shared<spdlog::logger>("", sink);
    auto call_logger = std::make_shared<spdlog::logger>(kCallLogger, sink);
    for (auto* logger : {main_logger.get(), call_logger.get()}) {
      logger->set_level(level);
      logger->flush_on(spdlog::level::info);
    }
    spdlog::drop(kCallLogger);
    spdlog::register_logger(call_logger);
    spdlog::set_default_logger(main_logger);
  } catch (const spdlog::spdlog_ex& e) {
    return std::string("--log-file: ") + e.what();
  }
  g_call_lines = options.call_lines;
  g_format = options.format;
  return std::nullopt;
}

bool call_line_wanted(bool server_fault) {
  if (!g_call_lines) return false;
  const auto logger = spdlog::get(kCallLogger);
  return logger && logger->should_log(server_fault ? spdlog::level::err : spdlog::level::info);
}

void log_call(const std::vector<LogField>& fields, bool server_fault) {
  if (!call_line_wanted(server_fault)) return;
  const auto logger = spdlog::get(kCallLogger);
  const spdlog::level::level_enum level = server_fault ? spdlog::level::err : spdlog::level::info;
  std::string line;
  for (const LogField& f : fields) {
    if (g_format == LogFormat::kJson) {
      if (!line.empty()) line += ',';
      line += json_string(f.key) + ":" + (f.is_number ? f.value : json_string(f.value));
    } else {
      if (!line.empty()) line += ' ';
      line += f.key + "=" + (f.is_number ? f.value : json_string(f.value));
    }
  }
  logger->log(level, line);
}

}  // namespace gk::server
