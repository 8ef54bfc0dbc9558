/// @file faults.cpp
/// Fault specs and the stream faults of FaultInjector (see faults.hpp).
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/faults.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <deque>
#include <optional>
#include <string>
#include <utility>

namespace duet {
namespace {

struct KindInfo {
  FaultKind kind;
  const char* name;
  enum Stream { kSensor, kOdometry, kEither, kNone } stream;
  double default_amount;
  double min_amount, max_amount;  // allowed range of the amount (inclusive)
  bool step;                      // an instant (no duration)
};

constexpr std::array<KindInfo, 12> kKinds{{
    {FaultKind::kCameraStop, "camera_stop", KindInfo::kSensor, 0.0, 0.0, 0.0, false},
    {FaultKind::kDepthZero, "depth_zero", KindInfo::kSensor, 0.0, 0.0, 0.0, false},
    {FaultKind::kDepthNoise, "depth_noise", KindInfo::kSensor, 0.0, 0.0, 0.0, false},
    {FaultKind::kColorBlack, "color_black", KindInfo::kSensor, 0.0, 0.0, 0.0, false},
    {FaultKind::kExtrinsics, "extrinsics", KindInfo::kSensor, 2.0, -45.0, 45.0, false},
    {FaultKind::kWheelSlip, "wheel_slip", KindInfo::kNone, 1.5, 0.0, 10.0, false},
    {FaultKind::kOdomJump, "odom_jump", KindInfo::kNone, 0.5, -10.0, 10.0, true},
    {FaultKind::kStampDisorder, "stamp_disorder", KindInfo::kEither, 0.0, 0.0, 0.0, false},
    {FaultKind::kStampDuplicate, "stamp_duplicate", KindInfo::kEither, 0.0, 0.0, 0.0, false},
    {FaultKind::kStampLate, "stamp_late", KindInfo::kEither, 0.5, 1e-3, 3600.0, false},
    {FaultKind::kClockBack, "clock_back", KindInfo::kNone, 1.0, 1e-3, 3600.0, true},
    {FaultKind::kKidnap, "kidnap", KindInfo::kNone, 0.5, -10.0, 10.0, true},
}};

const KindInfo& info(FaultKind k) {
  for (const auto& i : kKinds)
    if (i.kind == k) return i;
  fail(ErrorCode::kInternal, "unknown fault kind");
}

double number(std::string_view s, std::string_view spec, const char* what) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
    fail(ErrorCode::kInvalidArgument, "fault '" + std::string(spec) + "': " + what + " '" + std::string(s) + "' is not a finite number");
  return v;
}

}  // namespace

const char* to_string(FaultKind k) { return info(k).name; }

Fault parse_fault(std::string_view spec, std::size_t sensor_count) {
  const std::string sp(spec);
  auto bad = [&](const std::string& why) { fail(ErrorCode::kInvalidArgument, "fault '" + sp + "': " + why); };
  Fault f;
  f.spec = sp;
  const std::size_t at = spec.find('@');
  if (at == std::string_view::npos) bad("expected KIND[:SENSOR]@START[+DURATION][=AMOUNT]");
  std::string_view head = spec.substr(0, at), tail = spec.substr(at + 1);
  std::string_view sensor;
  if (const std::size_t c = head.find(':'); c != std::string_view::npos) {
    sensor = head.substr(c + 1);
    head = head.substr(0, c);
  }
  const KindInfo* k = nullptr;
  for (const auto& i : kKinds)
    if (head == i.name) k = &i;
  if (!k) {
    std::string names;
    for (const auto& i : kKinds) names += std::string(names.empty() ? "" : ", ") + i.name;
    bad("unknown kind '" + std::string(head) + "' (known: " + names + ")");
  }
  f.kind = k->kind;
  if (!sensor.empty()) {
    const double s = number(sensor, spec, "sensor");
    if (s != std::floor(s) || s < 0.0 || s > static_cast<double>(sensor_count))
      bad("sensor must be 1.." + std::to_string(sensor_count) + " (0: the odometry, for stamp faults), got " + std::string(sensor));
    f.sensor = static_cast<int>(s);
  }
  if (k->stream == KindInfo::kSensor && f.sensor < 1) bad(std::string(k->name) + " needs a sensor (" + k->name + ":1@...)");
  if (k->stream == KindInfo::kNone && !sensor.empty()) bad(std::string(k->name) + " takes no sensor");
  if (k->stream == KindInfo::kEither && sensor.empty()) bad(std::string(k->name) + " needs a stream: :0 (odometry) or :1.." + std::to_string(sensor_count));
  f.amount = k->default_amount;
  if (const std::size_t e = tail.find('='); e != std::string_view::npos) {
    if (k->min_amount == k->max_amount) bad(std::string(k->name) + " takes no amount");
    f.amount = number(tail.substr(e + 1), spec, "amount");
    if (f.amount < k->min_amount || f.amount > k->max_amount)
      bad("amount must be in [" + std::to_string(k->min_amount) + ", " + std::to_string(k->max_amount) + "], got " + std::to_string(f.amount));
    tail = tail.substr(0, e);
  }
  if (const std::size_t p = tail.find('+'); p != std::string_view::npos) {
    if (k->step) bad(std::string(k->name) + " is an instant: no duration");
    f.duration_s = number(tail.substr(p + 1), spec, "duration");
    if (!(f.duration_s > 0.0)) bad("duration must be > 0 s");
    tail = tail.substr(0, p);
  }
  f.start_s = number(tail, spec, "start");
  if (f.start_s < 0.0 || f.start_s > 1e6) bad("start must be in [0, 1e6] s");
  return f;
}

std::vector<Fault> parse_faults(std::span<const std::string> specs, std::size_t sensor_count) {
  std::vector<Fault> out;
  out.reserve(specs.size());
  for (const auto& s : specs) out.push_back(parse_fault(s, sensor_count));
  return out;
}

// ---- the injector ----------------------------------------------------------------------------

namespace {
double clock_shift(const std::vector<Fault>& faults, std::vector<std::uint64_t>& injected, double stamp) {
  double shift = 0.0;
  for (std::size_t i = 0; i < faults.size(); ++i)
    if (faults[i].kind == FaultKind::kClockBack && stamp >= faults[i].start_s) {
      shift -= faults[i].amount;
      ++injected[i];
    }
  return shift;
}
}  // namespace

/// The stamp faults of one stream: disorder holds a message back to deliver it after the next
/// one, duplicate copies, late holds messages until their stamp + amount.
template <class Msg>
class StampFaults {
 public:
  std::vector<Msg> apply(std::vector<Msg>&& in, double now_s, int stream, const std::vector<Fault>& faults,
                         std::vector<std::uint64_t>& injected) {
    std::vector<Msg> out;
    for (Msg& m : in) {
      const double t = m.stamp_s;
      bool consumed = false;
      for (std::size_t i = 0; i < faults.size() && !consumed; ++i) {
        const Fault& f = faults[i];
        if (f.sensor != stream || !f.active(t)) continue;
        if (f.kind == FaultKind::kStampLate) {
          late_.push_back({t + f.amount, std::move(m)});
          ++injected[i];
          consumed = true;
        } else if (f.kind == FaultKind::kStampDisorder) {
          if (held_) {
            out.push_back(std::move(m));  // the newer first ...
            out.push_back(std::move(*held_));  // ... then the older one
            held_.reset();
          } else {
            held_ = std::move(m);
          }
          ++injected[i];
          consumed = true;
        } else if (f.kind == FaultKind::kStampDuplicate) {
          out.push_back(copy(m));
          ++injected[i];
        }
      }
      if (!consumed) out.push_back(std::move(m));
    }
    // A held message goes out once its fault is over.
    if (held_ && !any_active(faults, stream, FaultKind::kStampDisorder, now_s)) {
      out.push_back(std::move(*held_));
      held_.reset();
    }
    while (!late_.empty() && late_.front().first <= now_s) {
      out.push_back(std::move(late_.front().second));
      late_.pop_front();
    }
    return out;
  }

 private:
  static bool any_active(const std::vector<Fault>& faults, int stream, FaultKind k, double t) {
    return std::any_of(faults.begin(), faults.end(), [&](const Fault& f) { return f.kind == k && f.sensor == stream && f.active(t); });
  }
  static Msg copy(const Msg& m) { return m; }
  std::optional<Msg> held_;
  std::deque<std::pair<double, Msg>> late_;
};

class FaultInjector::Chassis final : public ChassisInterface {
 public:
  Chassis(FaultInjector& owner, ChassisInterface& inner) : owner_(owner), inner_(inner) {}
  void command(const Twist& cmd) override { inner_.command(cmd); }
  std::vector<OdometryMsg> take_odometry() override {
    std::vector<OdometryMsg> in = inner_.take_odometry();
    const auto& faults = owner_.faults_;
    auto& injected = owner_.injected_;
    for (OdometryMsg& m : in) {
      // Slip: the wheels report more travel than the ground gave (the distance scaled; the
      // heading is the gyro's, as on a Kobuki).
      if (!have_raw_) {
        reported_ = m.pose;
        have_raw_ = true;
      } else {
        const Pose2 step = compose(inverse(last_raw_), m.pose);
        double factor = 1.0;
        for (std::size_t i = 0; i < faults.size(); ++i)
          if (faults[i].kind == FaultKind::kWheelSlip && faults[i].active(m.stamp_s)) {
            factor *= faults[i].amount;
            ++injected[i];
          }
        const float k = static_cast<float>(factor);
        reported_ = compose(reported_, Pose2{step.x * k, step.y * k, step.theta});  // the heading is the gyro's
      }
      last_raw_ = m.pose;
      Pose2 out = reported_;
      for (std::size_t i = 0; i < faults.size(); ++i)
        if (faults[i].kind == FaultKind::kOdomJump && m.stamp_s >= faults[i].start_s) {
          out = compose(Pose2{static_cast<float>(faults[i].amount), 0.0f, 0.0f}, out);  // in the odometry frame
          if (!jumped_[i]) ++injected[i];
          jumped_[i] = true;
        }
      m.pose = out;
      m.stamp_s += clock_shift(faults, injected, m.stamp_s);
    }
    return stamps_.apply(std::move(in), owner_.now_s_, 0, faults, injected);
  }
  void init(std::size_t n) { jumped_.assign(n, false); }

 private:
  FaultInjector& owner_;
  ChassisInterface& inner_;
  bool have_raw_ = false;
  Pose2 last_raw_, reported_;
  std::vector<bool> jumped_;
  StampFaults<OdometryMsg> stamps_;
};

class FaultInjector::Sensor final : public RgbdSensorInterface {
 public:
  Sensor(FaultInjector& owner, RgbdSensorInterface& inner, int number, std::uint64_t seed)
      : owner_(owner), inner_(inner), number_(number), rng_(seed) {}
  std::vector<StampedRgbd> take_frames() override {
    std::vector<StampedRgbd> in = inner_.take_frames();
    const auto& faults = owner_.faults_;
    auto& injected = owner_.injected_;
    std::vector<StampedRgbd> kept;
    for (StampedRgbd& f : in) {
      bool drop = false;
      for (std::size_t i = 0; i < faults.size(); ++i) {
        const Fault& ft = faults[i];
        if (ft.sensor != number_ || !ft.active(f.stamp_s)) continue;
        switch (ft.kind) {
          case FaultKind::kCameraStop: drop = true; break;
          case FaultKind::kDepthZero: std::fill(f.image.depth.begin(), f.image.depth.end(), std::uint16_t{0}); break;
          case FaultKind::kDepthNoise:
            for (auto& d : f.image.depth) d = static_cast<std::uint16_t>(rng_() & 0xFFFFu);
            break;
          case FaultKind::kColorBlack: std::fill(f.image.rgb.begin(), f.image.rgb.end(), std::uint8_t{0}); break;
          default: continue;  // stamp faults below; the simulator's own
        }
        ++injected[i];
      }
      f.stamp_s += clock_shift(faults, injected, f.stamp_s);
      if (drop) {
        inner_.recycle(std::move(f.image));
      } else {
        kept.push_back(std::move(f));
      }
    }
    return stamps_.apply(std::move(kept), owner_.now_s_, number_, faults, injected);
  }
  void recycle(RgbdImage&& image) override { inner_.recycle(std::move(image)); }

 private:
  FaultInjector& owner_;
  RgbdSensorInterface& inner_;
  int number_;
  std::mt19937_64 rng_;
  StampFaults<StampedRgbd> stamps_;
};

FaultInjector::FaultInjector(RobotSource& inner, std::vector<Fault> faults, std::uint64_t seed)
    : inner_(inner), faults_(std::move(faults)), injected_(faults_.size(), 0) {
  const auto inner_sensors = inner_.sensors();
  for (const Fault& f : faults_)
    if (f.sensor > static_cast<int>(inner_sensors.size()))
      fail(ErrorCode::kInvalidArgument, "fault '" + f.spec + "': the robot has " + std::to_string(inner_sensors.size()) + " sensors");
  chassis_ = std::make_unique<Chassis>(*this, inner_.chassis());
  chassis_->init(faults_.size());
  for (std::size_t i = 0; i < inner_sensors.size(); ++i) {
    sensors_.push_back(std::make_unique<Sensor>(*this, *inner_sensors[i], static_cast<int>(i) + 1, seed * 0x9E3779B97F4A7C15ull + i));
    ifaces_.push_back(sensors_.back().get());
  }
}

FaultInjector::~FaultInjector() = default;

ChassisInterface& FaultInjector::chassis() { return *chassis_; }
std::span<RgbdSensorInterface* const> FaultInjector::sensors() { return ifaces_; }

void FaultInjector::advance(double now_s) {
  now_s_ = now_s;
  inner_.advance(now_s);
}

std::vector<FaultCount> FaultInjector::counts() const {
  std::vector<FaultCount> out;
  for (std::size_t i = 0; i < faults_.size(); ++i) out.push_back({faults_[i], injected_[i]});
  return out;
}

void FaultInjector::count(std::size_t fault_index, std::uint64_t n) {
  if (fault_index < injected_.size()) injected_[fault_index] += n;
}

}  // namespace duet
