#pragma once
/// @file synchronizer.hpp
/// Approximate-time synchronisation of N message streams (issue 4: both RGB-D streams and the
/// wheel odometry), with the semantics of ROS message_filters' ApproximateTime policy
/// (http://wiki.ros.org/message_filters/ApproximateTime, ros_comm approximate_time.h):
///
///  - Every stream is a FIFO of stamped messages; stamps of one stream must not decrease.
///  - When every stream holds a message, the *pivot* is the latest of the streams' oldest
///    messages. Among the sets made of one message per stream that contain the pivot, the
///    synchroniser picks the one with the smallest cost (1 + age_penalty) * max_stamp - min_stamp
///    (the set's spread plus age_penalty times its end; among equal costs the oldest set), and
///    only when the first candidate's spread is at most max_interval_duration_s (later, better
///    candidates have a smaller spread).
///  - A set is emitted as soon as it is known to be optimal: when no later message can form a
///    better set (every later set must span [pivot stamp, current end]), using the optional
///    per-stream lower bounds on the interval between two messages to prove it earlier.
///  - Each message is used at most once; sets do not cross (per stream, the messages of a set
///    are later than those of every earlier set); messages older than an emitted set's message
///    of the same stream are dropped.
///
/// Drops are counted per stream and per reason (DropReason): a non-finite stamp, a stamp older
/// than the stream's previous one, a queue overflow (a stream holds more than queue_size
/// messages, e.g. because another stream is silent; the oldest is dropped), and "too old" (the
/// message can never be part of a set: older than the chosen set's message of its stream, or
/// no set within max_interval_duration_s can contain it).
///
/// Two layers:
///  - ApproximateTimeCore: index based. add(stream, stamp, id) with an opaque 64-bit id; emitted
///    sets and drops come back as ids (take_sets(), take_drops()).
///  - ApproximateTimeSync<T>: typed; owns the payloads (moved in, moved out in the emitted set,
///    destroyed when dropped; never copied), so heavy RGB-D frames and odometry can go through
///    one synchroniser with T = std::variant<...> or a struct.
///
/// Time: stamps in seconds on the runtime's clock (clock.hpp); the synchroniser never reads a
/// clock - it is driven purely by the stamps and the order of add() calls, so it is deterministic.
/// Thread safety: not thread-safe; one thread at a time (the runtime loop). Distinct objects are
/// independent.
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace duet {

struct ApproximateTimeSettings {
  /// Messages held per stream (queued plus examined for the current candidate), [1, 1e6].
  /// 10 (ROS's usual choice): 0.2 s of 50 Hz odometry, 0.33 s of 30 Hz frames - far more than
  /// the runtime's latency between two streams.
  std::size_t queue_size = 10;
  /// Largest allowed spread (max - min stamp) of an emitted set [s], [0, inf] (inf = no limit,
  /// ROS's default). 0.025 s: two free-running 30 Hz cameras are at most 16.7 ms apart and a
  /// 50 Hz odometry message is then within 20 ms of both, so every regular set of the dual
  /// profile fits, while a camera frame cannot be paired across a lost frame of the other
  /// camera when the two are in phase (as in the simulator).
  double max_interval_duration_s = 0.025;
  /// Weight of a set's age in the cost, [0, 1e6] (ROS default 0.1): > 0 prefers newer sets
  /// when spreads are close, which lowers latency.
  double age_penalty = 0.1;
  /// Per stream: a lower bound on the stamp interval between two consecutive messages [s],
  /// each finite and >= 0; empty = 0 for every stream (no bound; ROS's default). A true bound
  /// (e.g. 0.9 / rate) lets a set be proven optimal before the next message of every stream
  /// arrives. A message that violates its bound is kept but counted (StreamStats).
  std::vector<double> inter_message_lower_bounds_s;
};

/// Throws duet::Error(kInvalidArgument) naming the field and its allowed range.
void validate(const ApproximateTimeSettings& settings);

/// Why a message was dropped.
enum class DropReason : std::uint8_t {
  kNonFiniteStamp = 0,  ///< NaN or infinite stamp (refused by add())
  kOutOfOrder = 1,      ///< stamp older than the stream's previous accepted stamp (refused by add())
  kQueueOverflow = 2,   ///< the stream held more than queue_size messages; its oldest was dropped
  kTooOld = 3,          ///< can never be part of a set (see the file comment)
};
inline constexpr std::size_t kDropReasonCount = 4;
[[nodiscard]] const char* to_string(DropReason reason) noexcept;

struct StreamStats {
  std::uint64_t received = 0;          ///< add() calls for this stream
  std::uint64_t emitted = 0;           ///< messages that went out in a set
  std::array<std::uint64_t, kDropReasonCount> dropped{};  ///< by DropReason
  std::uint64_t bound_violations = 0;  ///< accepted messages closer than the stream's lower bound
  [[nodiscard]] std::uint64_t dropped_total() const noexcept {
    return dropped[0] + dropped[1] + dropped[2] + dropped[3];
  }
  [[nodiscard]] std::uint64_t dropped_by(DropReason r) const noexcept { return dropped[static_cast<std::size_t>(r)]; }
};

/// The index-based synchroniser (see the file comment). Invariant: for every stream,
/// received == emitted + dropped_total() + pending(stream).
class ApproximateTimeCore {
 public:
  /// One emitted set: ids[i] and stamps_s[i] belong to stream i.
  struct Set {
    std::vector<std::uint64_t> ids;
    std::vector<double> stamps_s;
  };
  struct Drop {
    std::size_t stream = 0;
    std::uint64_t id = 0;
    double stamp_s = 0.0;
    DropReason reason = DropReason::kTooOld;
  };

  /// `num_streams` in [2, 64]; settings are validated; inter_message_lower_bounds_s must be
  /// empty or have num_streams entries. Throws duet::Error(kInvalidArgument).
  ApproximateTimeCore(std::size_t num_streams, ApproximateTimeSettings settings = {});

  /// Offers a message. Returns true when it was accepted (queued; it will come back in a set
  /// or as a drop), false when it was refused at once (non-finite stamp or out of order;
  /// also reported by take_drops()). Throws kInvalidArgument for stream >= num_streams().
  bool add(std::size_t stream, double stamp_s, std::uint64_t id);

  /// The sets emitted since the last call, oldest first. Drain both lists after add() (they
  /// grow until taken).
  [[nodiscard]] std::vector<Set> take_sets();
  /// The drops since the last call, in the order they happened.
  [[nodiscard]] std::vector<Drop> take_drops();
  [[nodiscard]] bool has_sets() const noexcept { return !sets_.empty(); }
  [[nodiscard]] bool has_drops() const noexcept { return !drops_.empty(); }

  [[nodiscard]] std::size_t num_streams() const noexcept { return streams_.size(); }
  [[nodiscard]] const ApproximateTimeSettings& settings() const noexcept { return settings_; }
  [[nodiscard]] const StreamStats& stats(std::size_t stream) const;
  /// Messages of `stream` held (neither emitted nor dropped yet).
  [[nodiscard]] std::size_t pending(std::size_t stream) const;
  /// Sets emitted so far.
  [[nodiscard]] std::uint64_t sets_emitted() const noexcept { return sets_emitted_; }

 private:
  struct Entry {
    double stamp;
    std::uint64_t id;
  };
  struct Stream {
    std::deque<Entry> queue;  ///< not yet examined (front = oldest)
    std::vector<Entry> past;  ///< examined since the candidate was made (ROS's "past")
    bool has_dropped = false; ///< overflowed since it was last known not to be the best pivot
    double lower_bound = 0.0;
    double last_stamp = -std::numeric_limits<double>::infinity();
    StreamStats stats;
  };
  static constexpr std::size_t kNoPivot = static_cast<std::size_t>(-1);

  void process();
  void boundary(bool end, std::size_t& index, double& time) const;
  void virtual_boundary(bool end, std::size_t& index, double& time) const;
  [[nodiscard]] double virtual_time(std::size_t i) const;
  void make_candidate();
  void publish_candidate();
  void move_front_to_past(std::size_t i);
  void drop_front(std::size_t i, DropReason reason);
  void recover(std::size_t i, std::size_t count);
  void recover_all();
  void record_drop(std::size_t i, const Entry& e, DropReason reason);

  ApproximateTimeSettings settings_;
  std::vector<Stream> streams_;
  std::size_t non_empty_ = 0;  ///< streams whose queue is non-empty
  std::size_t pivot_ = kNoPivot;
  double pivot_time_ = 0.0;
  double candidate_start_ = 0.0;
  double candidate_end_ = 0.0;
  std::vector<Entry> candidate_;  ///< one per stream while pivot_ != kNoPivot
  std::vector<Set> sets_;
  std::vector<Drop> drops_;
  std::uint64_t sets_emitted_ = 0;
};

/// A stamped payload.
template <class T>
struct Stamped {
  double stamp_s = 0.0;
  T payload;
};

/// One synchronised set: messages[i] came from stream i.
template <class T>
struct SyncedSet {
  std::vector<Stamped<T>> messages;
  [[nodiscard]] double min_stamp_s() const {
    double m = std::numeric_limits<double>::infinity();
    for (const auto& s : messages) m = s.stamp_s < m ? s.stamp_s : m;
    return m;
  }
  [[nodiscard]] double max_stamp_s() const {
    double m = -std::numeric_limits<double>::infinity();
    for (const auto& s : messages) m = s.stamp_s > m ? s.stamp_s : m;
    return m;
  }
};

/// The typed synchroniser: ApproximateTimeCore plus payload ownership. T must be
/// move-constructible; it is never copied (a move-only T works). Payloads of dropped messages
/// are destroyed at the drop. Same thread-safety and determinism as the core.
template <class T>
class ApproximateTimeSync {
 public:
  ApproximateTimeSync(std::size_t num_streams, ApproximateTimeSettings settings = {})
      : core_(num_streams, std::move(settings)) {}

  /// Offers a message (the payload is moved in). Returns false when it was refused at once
  /// (non-finite or out-of-order stamp: the payload is destroyed and the drop counted).
  /// Throws kInvalidArgument for stream >= num_streams().
  bool add(std::size_t stream, double stamp_s, T payload) {
    std::uint64_t slot;
    if (!free_.empty()) {
      slot = free_.back();
      free_.pop_back();
      slots_[slot].emplace(std::move(payload));
    } else {
      slot = slots_.size();
      slots_.emplace_back(std::in_place, std::move(payload));
    }
    bool accepted = false;
    try {
      accepted = core_.add(stream, stamp_s, slot);
    } catch (...) {
      release(slot);
      throw;
    }
    collect();
    return accepted;
  }

  /// The sets emitted since the last call, oldest first.
  [[nodiscard]] std::vector<SyncedSet<T>> take_sets() {
    std::vector<SyncedSet<T>> out;
    out.reserve(ready_.size());
    while (!ready_.empty()) {
      out.push_back(std::move(ready_.front()));
      ready_.pop_front();
    }
    return out;
  }
  /// The oldest emitted set not yet taken, if any.
  [[nodiscard]] std::optional<SyncedSet<T>> pop() {
    if (ready_.empty()) return std::nullopt;
    std::optional<SyncedSet<T>> s(std::move(ready_.front()));
    ready_.pop_front();
    return s;
  }
  [[nodiscard]] bool has_set() const noexcept { return !ready_.empty(); }

  /// Called (synchronously, inside add()) for every drop, with the stream, stamp and reason
  /// (Drop::id is an internal slot number); the payload is already destroyed. Optional: the
  /// counts are always in stats(). Pass an empty function to remove it.
  void set_drop_callback(std::function<void(const ApproximateTimeCore::Drop&)> callback) {
    on_drop_ = std::move(callback);
  }

  [[nodiscard]] std::size_t num_streams() const noexcept { return core_.num_streams(); }
  [[nodiscard]] const StreamStats& stats(std::size_t stream) const { return core_.stats(stream); }
  [[nodiscard]] std::size_t pending(std::size_t stream) const { return core_.pending(stream); }
  [[nodiscard]] std::uint64_t sets_emitted() const noexcept { return core_.sets_emitted(); }
  [[nodiscard]] const ApproximateTimeCore& core() const noexcept { return core_; }

 private:
  void release(std::uint64_t slot) {
    slots_[slot].reset();
    free_.push_back(slot);
  }
  void collect() {
    if (core_.has_drops()) {
      for (auto& d : core_.take_drops()) {
        release(d.id);
        if (on_drop_) on_drop_(d);
      }
    }
    if (core_.has_sets()) {
      for (auto& s : core_.take_sets()) {
        SyncedSet<T> out;
        out.messages.reserve(s.ids.size());
        for (std::size_t i = 0; i < s.ids.size(); ++i) {
          out.messages.push_back(Stamped<T>{s.stamps_s[i], std::move(*slots_[s.ids[i]])});
          release(s.ids[i]);
        }
        ready_.push_back(std::move(out));
      }
    }
  }

  ApproximateTimeCore core_;
  std::vector<std::optional<T>> slots_;
  std::vector<std::uint64_t> free_;
  std::deque<SyncedSet<T>> ready_;
  std::function<void(const ApproximateTimeCore::Drop&)> on_drop_;
};

}  // namespace duet
