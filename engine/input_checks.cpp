#include "engine/input_checks.h"

#include "kernel/core/tolerances.h"

#include <cctype>
#include <cmath>

namespace gk::engine {

Result<bool> check_id(const std::string& id, const std::string& field) {
  if (id.empty() || id.size() > kMaxIdLength)
    return invalid_argument(field, "must be 1 to " + std::to_string(kMaxIdLength) + " characters");
  for (char c : id)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' || c == ':'))
      return invalid_argument(field, "may hold only letters, digits and - _ . :");
  return true;
}

Result<bool> check_label(const std::string& text, const std::string& field) {
  if (text.size() > kMaxLabelLength) return invalid_argument(field, "longer than " + std::to_string(kMaxLabelLength) + " bytes");
  const auto byte = [&](std::size_t i) { return i < text.size() ? static_cast<unsigned char>(text[i]) : 0u; };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const unsigned c = byte(i);
    // C0 controls and DEL; in UTF-8 the C1 controls (U+0080-U+009F), the line and paragraph
    // separators (U+2028, U+2029) and the bidirectional overrides and isolates (U+202A-U+202E,
    // U+2066-U+2069), which make a name read differently from what it holds.
    const bool c1 = c == 0xC2 && byte(i + 1) >= 0x80 && byte(i + 1) <= 0x9F;
    const bool separator_or_bidi = c == 0xE2 && ((byte(i + 1) == 0x80 && byte(i + 2) >= 0xA8 && byte(i + 2) <= 0xAE) ||
                                                 (byte(i + 1) == 0x81 && byte(i + 2) >= 0xA6 && byte(i + 2) <= 0xA9));
    if (c < 0x20 || c == 0x7F || c1 || separator_or_bidi)
      return invalid_argument(field, "holds a control or bidirectional formatting character (NUL, newline, DEL, U+202E, ...)");
  }
  return true;
}

Result<StoredPose> checked_pose(const Vec3& translation, const Vec3& axis, double angle_deg, const std::string& field) {
  if (!translation.allFinite()) return invalid_argument(field + ".translation", "must be finite");
  if (!std::isfinite(angle_deg)) return invalid_argument(field + ".rotation_deg", "must be finite");
  if (std::abs(angle_deg) > kMaxAngleDeg) return invalid_argument(field + ".rotation_deg", "beyond 1e6 degrees either way");
  if (translation.cwiseAbs().maxCoeff() > tolerances::kMaxCoordinateMm)
    return invalid_argument(field + ".translation", "beyond 1e7 mm from the origin");
  StoredPose pose;
  pose.translation = translation;
  if (angle_deg == 0.0) return pose;
  const double largest = axis.allFinite() ? axis.cwiseAbs().maxCoeff() : 0.0;
  if (!(largest > 0.0)) return invalid_argument(field + ".rotation_axis", "must be a finite, non-zero vector");
  // Scaled before normalising: (1e200, 0, 1) squared would overflow to infinity.
  pose.axis = axis / largest;
  pose.angle_deg = angle_deg;
  if (!pose.transform().is_rigid()) return invalid_argument(field + ".rotation_axis", "does not give a rigid rotation");
  return pose;
}

}  // namespace gk::engine
