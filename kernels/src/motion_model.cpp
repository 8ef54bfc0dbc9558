#include <duet/kernels/error.hpp>
#include <duet/kernels/motion_model.hpp>

#include <string>

namespace duet {

void validate(const ChassisLimits& l) {
  auto bad = [](const char* key, float v, const char* range) {
    fail(ErrorCode::kInvalidArgument,
         std::string("ChassisLimits.") + key + " = " + std::to_string(v) + " is outside " + range);
  };
  if (!std::isfinite(l.max_v_mps) || !(l.max_v_mps > 0.0f)) bad("max_v_mps", l.max_v_mps, "(0, inf)");
  if (!std::isfinite(l.min_v_mps) || l.min_v_mps > 0.0f) bad("min_v_mps", l.min_v_mps, "(-inf, 0]");
  if (!std::isfinite(l.max_omega_rps) || !(l.max_omega_rps > 0.0f))
    bad("max_omega_rps", l.max_omega_rps, "(0, inf)");
  if (!std::isfinite(l.max_accel_mps2) || !(l.max_accel_mps2 > 0.0f))
    bad("max_accel_mps2", l.max_accel_mps2, "(0, inf)");
  if (!std::isfinite(l.max_alpha_rps2) || !(l.max_alpha_rps2 > 0.0f))
    bad("max_alpha_rps2", l.max_alpha_rps2, "(0, inf)");
}

}  // namespace duet
