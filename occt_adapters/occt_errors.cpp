#include "occt_adapters/occt_errors.h"

#include <Standard_Failure.hxx>

#include <exception>

namespace gk::occt {

Result<bool> guarded(const std::string& field, const std::string& what, const std::function<void()>& body) {
  try {
    body();
    return true;
  } catch (const Standard_Failure& failure) {
    const char* message = failure.GetMessageString();
    return invalid_argument(field, what + " failed in OpenCASCADE: " + failure.DynamicType()->Name() +
                                       (message && *message ? std::string(": ") + message : std::string()));
  } catch (const std::exception& e) {
    return invalid_argument(field, what + " failed: " + e.what());
  }
}

}  // namespace gk::occt
