/// Fuzz target: a robot profile (YAML) through load_profile, with the input's last line (a
/// YAML comment: its '#' dropped) also tried as a --set overlay. A profile that loads must
/// survive to_yaml and load again to the same text (the profile command prints what it runs).
#include "fuzz_util.hpp"

#include <duet/runtime/config/profile.hpp>

#include <array>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto path = duet::fuzz::put("profile.yaml", text);
  try {
    const std::size_t nl = text.rfind('\n');
    std::string_view last = nl == std::string_view::npos ? text : text.substr(nl + 1);
    if (!last.empty() && last.front() == '#') last.remove_prefix(1);  // a YAML comment to the file
    std::vector<duet::ProfileOverlay> overlays;
    try {
      overlays.push_back(duet::set_overlay(last));
    } catch (const duet::Error&) {
    }
    const duet::Profile p = duet::load_profile(path, overlays);
    const std::string yaml = duet::to_yaml(p);
    const duet::Profile again = duet::parse_profile(yaml, "to_yaml");
    if (duet::to_yaml(again) != yaml) std::abort();  // printing then reading must be the identity
    duet::fuzz::accepted(overlays.empty() ? "profile" : "profile with the last line as --set");
  } catch (const duet::Error& e) {
    duet::fuzz::refused(e);
  }
  return 0;
}
