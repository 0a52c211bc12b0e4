// The daemon's log: its format (text for people, or one JSON object per line for log collectors)
// and one line per answered call with its request id, outcome, latency and, where the answer has
// one, its verdict and deciding stage. Configured once at start-up (main.cpp); the service writes
// the call lines (server/call.h).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace gk::server {

enum class LogFormat {
  kText,  // spdlog's usual lines
  kJson,  // one JSON object per line: time, level, logger, msg, and the fields of call lines
};

struct LogOptions {
  LogFormat format = LogFormat::kText;
  std::string level = "info";   // trace, debug, info, warn, error
  std::string file;             // empty: standard error
  bool call_lines = true;       // one line per answered call (see log_call)
};

// Replaces the default logger (and the call logger) by ones with these options; an error names
// the option (an unknown level, a file that cannot be opened).
std::optional<std::string> configure_logging(const LogOptions& options);
std::optional<LogFormat> log_format_named(const std::string& name);  // "text" or "json"

// One field of a call line: its value quoted as a JSON string, or written as a JSON number.
struct LogField {
  std::string key;
  std::string value;
  bool is_number = false;
};

// Writes one call line (nothing when call lines are off or the level excludes it): at info, or at
// error when the daemon itself failed the call (INTERNAL, UNKNOWN, DATA_LOSS). What a client got
// wrong (a bad field, an unknown id) is info: it is the client's to fix, not the operator's.
void log_call(const std::vector<LogField>& fields, bool server_fault);
// Whether log_call would write that line (cheap: a call's fields are only gathered when it would).
bool call_line_wanted(bool server_fault);

// The text of a JSON string literal (with its quotes) for any bytes: control characters and
// invalid UTF-8 are escaped, so that a line is always one valid JSON value.
std::string json_string(const std::string& text);

}  // namespace gk::server
