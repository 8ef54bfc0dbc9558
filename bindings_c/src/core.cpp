// The handle registry, error reporting, the device and the version (duet.h).
#include "capi_internal.hpp"

#include <deque>
#include <duet_version.h>

#include <tbb/info.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <limits>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace duet::capi {
namespace {

constexpr unsigned kKindBits = 4;

// ---- registry ------------------------------------------------------------------------------

struct Entry {
  std::shared_ptr<Object> object;
  std::int64_t refs = 0;
};

struct Registry {
  std::mutex mutex;
  std::unordered_map<std::uint64_t, Entry> live;
  std::uint64_t next_id = 1;
  /// Released handles -> their creating device (the latest kDeadKept), so that an error about a
  /// released handle reaches that device while it lives.
  static constexpr std::size_t kDeadKept = 65536;
  std::unordered_map<std::uint64_t, std::uint64_t> dead;
  std::deque<std::uint64_t> dead_order;
  void bury(std::uint64_t key, std::uint64_t parent) {
    if (parent == 0) return;
    try {
      if (dead.emplace(key, parent).second) dead_order.push_back(key);
      while (dead_order.size() > kDeadKept) {
        dead.erase(dead_order.front());
        dead_order.pop_front();
      }
    } catch (...) {
      // Out of memory: the error goes to the no-device slot instead.
    }
  }
};

Registry& registry() {
  // Leaked on purpose: handles may be released from static destructors of the application.
  static Registry* r = new Registry();
  return *r;
}

std::uint64_t key_of(const void* handle) noexcept {
  return static_cast<std::uint64_t>(reinterpret_cast<std::uintptr_t>(handle));
}

std::string handle_text(const void* handle) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%p", handle);
  return buf;
}

// ---- the no-device error slot ----------------------------------------------------------------

struct NoDeviceSlot {
  duet_error first_error = DUET_ERROR_NONE;
  std::string last_message;
};

NoDeviceSlot& no_device_slot() {
  thread_local NoDeviceSlot slot;
  return slot;
}

struct GlobalCallback {
  std::mutex mutex;
  duet_error_callback callback = nullptr;
  void* user = nullptr;
};

GlobalCallback& global_callback() {
  static GlobalCallback* g = new GlobalCallback();
  return *g;
}

// Copy handed out by duet_device_get_error_message (valid until the next call on the thread).
std::string& message_return_buffer() {
  thread_local std::string s;
  return s;
}

// ---- configuration -------------------------------------------------------------------------

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

int parse_int(std::string_view key, std::string_view value, int lo, int hi) {
  int v = 0;
  const char* b = value.data();
  const char* e = value.data() + value.size();
  auto [p, ec] = std::from_chars(b, e, v);
  if (value.empty() || ec != std::errc() || p != e || v < lo || v > hi) {
    invalid_argument("bad value '" + std::string(value) + "' for key '" + std::string(key) +
                     "' (allowed: integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                     "])");
  }
  return v;
}

struct DeviceConfig {
  int threads = 0;
  bool verbose = false;
};

DeviceConfig parse_config(const char* config) {
  DeviceConfig c;
  if (config == nullptr) return c;
  std::string_view rest(config);
  bool seen_threads = false, seen_verbose = false;
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view token = trim(rest.substr(0, comma));
    if (!token.empty()) {
      const std::size_t eq = token.find('=');
      if (eq == std::string_view::npos) {
        invalid_argument("configuration token '" + std::string(token) +
                         "' is not key=value (keys: threads, verbose)");
      }
      const std::string_view key = trim(token.substr(0, eq));
      const std::string_view value = trim(token.substr(eq + 1));
      if (key == "threads") {
        if (seen_threads) invalid_argument("configuration key 'threads' given twice");
        seen_threads = true;
        c.threads = parse_int(key, value, 0, 1024);
      } else if (key == "verbose") {
        if (seen_verbose) invalid_argument("configuration key 'verbose' given twice");
        seen_verbose = true;
        c.verbose = parse_int(key, value, 0, 1) != 0;
      } else {
        invalid_argument("unknown configuration key '" + std::string(key) +
                         "' (keys: threads, verbose)");
      }
    }
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return c;
}

}  // namespace

// ---- shared helpers ------------------------------------------------------------------------

const char* kind_name(Kind kind) noexcept {
  switch (kind) {
    case Kind::kDevice: return "duet_device";
    case Kind::kCloud: return "duet_cloud";
    case Kind::kGrid: return "duet_grid";
    case Kind::kPlanner: return "duet_planner";
    case Kind::kRuntime: return "duet_runtime";
    case Kind::kSim: return "duet_sim";
  }
  return "unknown handle";
}

duet_error map_error_code(ErrorCode code) noexcept {
  switch (code) {
    case ErrorCode::kInvalidArgument: return DUET_ERROR_INVALID_ARGUMENT;
    case ErrorCode::kOutOfRange: return DUET_ERROR_OUT_OF_RANGE;
    case ErrorCode::kIo: return DUET_ERROR_IO;
    case ErrorCode::kParse: return DUET_ERROR_PARSE;
    case ErrorCode::kUnsupported: return DUET_ERROR_UNSUPPORTED;
    case ErrorCode::kOutOfMemory: return DUET_ERROR_OUT_OF_MEMORY;
    case ErrorCode::kInternal: return DUET_ERROR_UNKNOWN;
  }
  return DUET_ERROR_UNKNOWN;
}

void report(Device* device, duet_error code, const char* fn, const char* message) noexcept {
  std::string text;
  try {
    text = std::string(fn) + ": " + message;
  } catch (...) {
    // Out of memory while building the message: keep the code, drop the text.
  }
  duet_error_callback cb = nullptr;
  void* user = nullptr;
  bool verbose = false;
  if (device != nullptr) {
    std::lock_guard lock(device->error_mutex);
    if (device->first_error == DUET_ERROR_NONE) {  // the message stays the one of the code get_error returns
      device->first_error = code;
      try {
        device->last_message = text;
      } catch (...) {
        device->last_message.clear();
      }
    }
    cb = device->callback;
    user = device->callback_user;
    verbose = device->verbose;
  } else {
    NoDeviceSlot& slot = no_device_slot();
    if (slot.first_error == DUET_ERROR_NONE) {
      slot.first_error = code;
      try {
        slot.last_message = text;
      } catch (...) {
        slot.last_message.clear();
      }
    }
    GlobalCallback& g = global_callback();
    std::lock_guard lock(g.mutex);
    cb = g.callback;
    user = g.user;
  }
  if (verbose) std::fprintf(stderr, "duet: %s: %s\n", duet_error_string(code), text.c_str());
  // Not re-entered: an error raised by a duet call made inside a callback is recorded but calls
  // no callback (found by fuzz_capi: a callback whose own call failed recursed until the stack
  // overflowed).
  static thread_local bool in_callback = false;
  if (cb != nullptr && !in_callback) {
    in_callback = true;
    try {
      cb(user, code, text.c_str());
    } catch (...) {
      // A C++ callback that throws must not unwind through C frames.
    }
    in_callback = false;
  }
}

std::uint64_t register_object(std::shared_ptr<Object> obj) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  if (obj->parent != 0) {
    auto it = r.live.find(obj->parent);
    if (it == r.live.end()) api_fail(DUET_ERROR_INVALID_OPERATION, "device was released");
    ++it->second.refs;
  }
  const std::uint64_t parent = obj->parent;
  const std::uint64_t key = (r.next_id++ << kKindBits) | static_cast<std::uint64_t>(obj->kind);
  obj->key = key;
  try {
    r.live.emplace(key, Entry{std::move(obj), 1});
  } catch (...) {
    if (auto it = r.live.find(parent); parent != 0 && it != r.live.end()) --it->second.refs;
    throw;
  }
  return key;
}

std::shared_ptr<Object> lookup(const void* handle, Kind expected, const char* fn,
                               const char* arg, bool to_owner) noexcept {
  duet_error code = DUET_ERROR_NONE;
  std::string message;
  std::shared_ptr<Device> owner;  // where the error goes: the handle's device if known and alive
  try {
    if (handle == nullptr) {
      code = DUET_ERROR_INVALID_ARGUMENT;
      message = std::string(arg) + " is NULL (expected a " + kind_name(expected) + ")";
    } else {
      std::shared_ptr<Object> obj;
      {
        Registry& r = registry();
        std::lock_guard lock(r.mutex);
        auto it = r.live.find(key_of(handle));
        if (it != r.live.end()) obj = it->second.object;
        // The device the handle belongs to, if it is known and alive: the error goes there.
        std::uint64_t dev_key = 0;
        if (obj) dev_key = obj->kind == Kind::kDevice ? obj->key : obj->parent;
        else if (auto d = r.dead.find(key_of(handle)); d != r.dead.end()) dev_key = d->second;
        if (auto dv = (dev_key && to_owner) ? r.live.find(dev_key) : r.live.end(); dv != r.live.end() && dv->second.object->kind == Kind::kDevice)
          owner = std::static_pointer_cast<Device>(dv->second.object);
      }
      if (obj && obj->kind == expected) return obj;
      code = DUET_ERROR_INVALID_OPERATION;
      if (!obj) {
        message = std::string(arg) + " " + handle_text(handle) + " is not a live " +
                  kind_name(expected) + " (released, or never created by duet)";
      } else {
        message = std::string(arg) + " " + handle_text(handle) + " is a " + kind_name(obj->kind) +
                  ", expected a " + kind_name(expected);
      }
    }
  } catch (...) {
    if (code == DUET_ERROR_NONE) code = DUET_ERROR_OUT_OF_MEMORY;
    message.clear();
  }
  report(owner.get(), code, fn, message.empty() ? "invalid handle" : message.c_str());
  return nullptr;
}

void retain_handle(const void* handle, Kind expected, const char* fn) noexcept {
  std::shared_ptr<Object> obj = lookup(handle, expected, fn, "handle");
  if (!obj) return;
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  auto it = r.live.find(obj->key);
  if (it == r.live.end()) {
    // Released by another thread between the lookup and here.
    report(nullptr, DUET_ERROR_INVALID_OPERATION, fn, "handle was released concurrently");
    return;
  }
  ++it->second.refs;
}

void release_handle(const void* handle, Kind expected, const char* fn) noexcept {
  std::shared_ptr<Object> obj = lookup(handle, expected, fn, "handle");
  if (!obj) return;
  std::vector<std::shared_ptr<Object>> graveyard;  // destroyed after the lock is dropped
  bool lost = false;
  {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    std::uint64_t key = obj->key;
    auto it = r.live.find(key);
    if (it == r.live.end()) {
      lost = true;
    } else {
      // Dropping the last reference of a cloud/grid also drops its reference on the device.
      while (it != r.live.end() && --it->second.refs == 0) {
        const std::uint64_t parent = it->second.object->parent;
        try {
          graveyard.push_back(std::move(it->second.object));
        } catch (...) {
          // Could not keep it for later destruction: it dies here, under the lock.
        }
        r.bury(it->first, parent);
        r.live.erase(it);
        it = parent != 0 ? r.live.find(parent) : r.live.end();
      }
    }
  }
  for (const auto& o : graveyard)
    if (o) o->released();  // the last handle reference is gone (a runtime stops its thread)
  obj.reset();
  graveyard.clear();
  if (lost) report(nullptr, DUET_ERROR_INVALID_OPERATION, fn, "handle was released concurrently");
}

std::size_t check_buffer(const void* ptr, std::size_t stride, std::size_t count,
                         std::size_t elem_size, std::size_t align, const char* name) {
  if (stride == 0) stride = elem_size;
  if (count == 0) return stride;
  if (ptr == nullptr) {
    invalid_argument(std::string(name) + " is NULL but count is " + std::to_string(count));
  }
  if (stride < elem_size) {
    invalid_argument(std::string(name) + " stride " + std::to_string(stride) +
                     " bytes is smaller than its element (" + std::to_string(elem_size) +
                     " bytes)");
  }
  if (stride % align != 0) {
    invalid_argument(std::string(name) + " stride " + std::to_string(stride) +
                     " bytes is not a multiple of " + std::to_string(align));
  }
  if (reinterpret_cast<std::uintptr_t>(ptr) % align != 0) {
    invalid_argument(std::string(name) + " is not " + std::to_string(align) + "-byte aligned");
  }
  const std::size_t max = std::numeric_limits<std::size_t>::max();
  if (count - 1 > (max - elem_size) / stride ||
      reinterpret_cast<std::uintptr_t>(ptr) > max - ((count - 1) * stride + elem_size)) {
    invalid_argument(std::string(name) + ": " + std::to_string(count) + " elements at stride " +
                     std::to_string(stride) + " exceed the address space");
  }
  return stride;
}

void check_count(std::size_t expected, std::size_t given, const char* name) {
  if (expected != given) {
    invalid_argument(std::string(name) + ": expected " + std::to_string(expected) +
                     " elements, given " + std::to_string(given));
  }
}

void check_not_null(const void* ptr, const char* name) {
  if (ptr == nullptr) invalid_argument(std::string(name) + " is NULL");
}

Device::Device(int threads, bool verbose_)
    : Object(Kind::kDevice),
      // More threads than TBB may use would only make TBB print warnings: clamp.
      arena(threads == 0 ? tbb::task_arena::automatic
                         : std::min(threads, tbb::info::default_concurrency())),
      thread_count((arena.initialize(), arena.max_concurrency())),
      verbose(verbose_) {}

}  // namespace duet::capi

using namespace duet::capi;

extern "C" {

DUET_API int duet_get_version(void) { return DUET_VERSION; }

DUET_API const char* duet_get_version_string(void) { return DUET_VERSION_STRING; }

DUET_API const char* duet_error_string(enum duet_error code) {
  switch (enum_value(code)) {
    case DUET_ERROR_NONE: return "DUET_ERROR_NONE";
    case DUET_ERROR_INVALID_ARGUMENT: return "DUET_ERROR_INVALID_ARGUMENT";
    case DUET_ERROR_INVALID_OPERATION: return "DUET_ERROR_INVALID_OPERATION";
    case DUET_ERROR_OUT_OF_RANGE: return "DUET_ERROR_OUT_OF_RANGE";
    case DUET_ERROR_IO: return "DUET_ERROR_IO";
    case DUET_ERROR_PARSE: return "DUET_ERROR_PARSE";
    case DUET_ERROR_UNSUPPORTED: return "DUET_ERROR_UNSUPPORTED";
    case DUET_ERROR_OUT_OF_MEMORY: return "DUET_ERROR_OUT_OF_MEMORY";
    case DUET_ERROR_UNKNOWN: return "DUET_ERROR_UNKNOWN";
  }
  return "DUET_ERROR_?";
}

DUET_API duet_device duet_device_new(const char* config) {
  duet_device result = nullptr;
  guarded(nullptr, "duet_device_new", [&] {
    const auto c = parse_config(config);
    auto device = std::make_shared<Device>(c.threads, c.verbose);
    result = to_handle<duet_device>(register_object(std::move(device)));
  });
  return result;
}

DUET_API void duet_device_retain(duet_device device) {
  retain_handle(device, Kind::kDevice, "duet_device_retain");
}

DUET_API void duet_device_release(duet_device device) {
  release_handle(device, Kind::kDevice, "duet_device_release");
}

DUET_API int duet_device_get_thread_count(duet_device device) {
  auto d = resolve<Device>(device, "duet_device_get_thread_count", "device");
  return d ? d->thread_count : 0;
}

DUET_API enum duet_error duet_device_get_error(duet_device device) {
  if (device == nullptr) {
    NoDeviceSlot& slot = no_device_slot();
    return std::exchange(slot.first_error, DUET_ERROR_NONE);
  }
  NoDeviceSlot& slot = no_device_slot();
  const duet_error pending = slot.first_error;
  auto d = resolve<Device>(device, "duet_device_get_error", "device", false);
  if (!d) {
    // The failure was recorded in the no-device slot (message, callback); hand the code out
    // right away instead of leaving it pending there.
    slot.first_error = pending;
    return DUET_ERROR_INVALID_OPERATION;
  }
  std::lock_guard lock(d->error_mutex);
  return std::exchange(d->first_error, DUET_ERROR_NONE);
}

DUET_API const char* duet_device_get_error_message(duet_device device) {
  std::string& out = message_return_buffer();
  try {
    if (device == nullptr) {
      out = no_device_slot().last_message;
    } else if (auto d = resolve<Device>(device, "duet_device_get_error_message", "device", false)) {
      std::lock_guard lock(d->error_mutex);
      out = d->last_message;
    } else {
      out = no_device_slot().last_message;
    }
  } catch (...) {
    out.clear();
  }
  return out.c_str();
}

DUET_API void duet_device_set_error_callback(duet_device device, duet_error_callback callback,
                                             void* user_ptr) {
  if (device == nullptr) {
    GlobalCallback& g = global_callback();
    std::lock_guard lock(g.mutex);
    g.callback = callback;
    g.user = callback != nullptr ? user_ptr : nullptr;
    return;
  }
  auto d = resolve<Device>(device, "duet_device_set_error_callback", "device");
  if (!d) return;
  std::lock_guard lock(d->error_mutex);
  d->callback = callback;
  d->callback_user = callback != nullptr ? user_ptr : nullptr;
}

}  // extern "C"
