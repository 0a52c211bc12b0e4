// Every OCCT call from this module runs inside guarded(): Standard_Failure and std::exception
// become an Error naming the operation, so no OCCT exception crosses the module boundary.
#pragma once

#include "kernel/core/status.h"

#include <functional>
#include <string>

namespace gk::occt {

// Runs body; an exception becomes invalid_argument(field, "<what>: <exception message>").
Result<bool> guarded(const std::string& field, const std::string& what, const std::function<void()>& body);

}  // namespace gk::occt
