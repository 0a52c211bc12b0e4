// What a client may name things: checked before anything is stored.
#pragma once

#include "kernel/core/status.h"

#include <cstddef>
#include <string>

namespace gk::engine {

// Ids a client names (objects, machines): 1-128 of [A-Za-z0-9-_.:], so that nothing stored is
// truncated or ambiguous (a NUL byte ended an id in storage). Names, categories and groups: at most
// 256 bytes, no control characters.
inline constexpr std::size_t kMaxIdLength = 128;
inline constexpr std::size_t kMaxLabelLength = 256;
Result<bool> check_id(const std::string& id, const std::string& field);
Result<bool> check_label(const std::string& text, const std::string& field);

}  // namespace gk::engine
