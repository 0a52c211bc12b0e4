// Reads B-Rep parts: STEP (.step/.stp), OCCT BREP (.brep) and IGES (.igs/.iges).
#pragma once

#include "kernel/core/status.h"
#include "occt_adapters/shape.h"

#include <string>

namespace gk::occt {

// Every shape in the file as one compound. Missing, unreadable or empty files are errors naming
// the file; OCCT exceptions are caught.
Result<Shape> read_shape_file(const std::string& path);

// The same from bytes; format is "step", "brep" or "iges".
Result<Shape> read_shape_bytes(const std::string& bytes, const std::string& format);

}  // namespace gk::occt
