// A number for a human-readable reason or method text: six significant digits.
#pragma once

#include <sstream>
#include <string>

namespace gk::engine {

inline std::string number_text(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

}  // namespace gk::engine
