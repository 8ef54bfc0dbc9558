// ApproximateTime synchronisation (ROS message_filters semantics; see synchronizer.hpp).
// The algorithm follows ros_comm's approximate_time.h step by step (pivot, candidate, "past"
// messages, virtual search with the inter-message lower bounds), generalised to N streams at
// run time and with every drop counted.
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/synchronizer.hpp>

#include <cmath>
#include <string>

namespace duet {

const char* to_string(DropReason reason) noexcept {
  switch (reason) {
    case DropReason::kNonFiniteStamp: return "non-finite stamp";
    case DropReason::kOutOfOrder: return "out-of-order stamp";
    case DropReason::kQueueOverflow: return "queue overflow";
    case DropReason::kTooOld: return "too old";
  }
  return "unknown";
}

void validate(const ApproximateTimeSettings& s) {
  auto bad = [](const std::string& key, double v, const char* range) {
    fail(ErrorCode::kInvalidArgument,
         "ApproximateTimeSettings." + key + " = " + std::to_string(v) + " is outside " + range);
  };
  if (s.queue_size < 1 || s.queue_size > 1000000)
    bad("queue_size", static_cast<double>(s.queue_size), "[1, 1000000]");
  if (std::isnan(s.max_interval_duration_s) || s.max_interval_duration_s < 0.0)
    bad("max_interval_duration_s", s.max_interval_duration_s, "[0, inf]");
  if (!std::isfinite(s.age_penalty) || s.age_penalty < 0.0 || s.age_penalty > 1e6)
    bad("age_penalty", s.age_penalty, "[0, 1e6]");
  for (std::size_t i = 0; i < s.inter_message_lower_bounds_s.size(); ++i) {
    const double b = s.inter_message_lower_bounds_s[i];
    if (!std::isfinite(b) || b < 0.0)
      bad("inter_message_lower_bounds_s[" + std::to_string(i) + "]", b, "[0, inf) (finite)");
  }
}

ApproximateTimeCore::ApproximateTimeCore(std::size_t num_streams, ApproximateTimeSettings settings)
    : settings_(std::move(settings)) {
  if (num_streams < 2 || num_streams > 64)
    fail(ErrorCode::kInvalidArgument,
         "ApproximateTimeCore: num_streams = " + std::to_string(num_streams) + " is outside [2, 64]");
  validate(settings_);
  const auto& lb = settings_.inter_message_lower_bounds_s;
  if (!lb.empty() && lb.size() != num_streams)
    fail(ErrorCode::kInvalidArgument, "ApproximateTimeSettings.inter_message_lower_bounds_s has " +
                                          std::to_string(lb.size()) + " entries; expected 0 or num_streams = " +
                                          std::to_string(num_streams));
  streams_.resize(num_streams);
  for (std::size_t i = 0; i < num_streams; ++i) streams_[i].lower_bound = lb.empty() ? 0.0 : lb[i];
}

const StreamStats& ApproximateTimeCore::stats(std::size_t stream) const {
  if (stream >= streams_.size())
    fail(ErrorCode::kInvalidArgument, "ApproximateTimeCore::stats: stream " + std::to_string(stream) +
                                          " is outside [0, " + std::to_string(streams_.size()) + ")");
  return streams_[stream].stats;
}

std::size_t ApproximateTimeCore::pending(std::size_t stream) const {
  if (stream >= streams_.size())
    fail(ErrorCode::kInvalidArgument, "ApproximateTimeCore::pending: stream " + std::to_string(stream) +
                                          " is outside [0, " + std::to_string(streams_.size()) + ")");
  return streams_[stream].queue.size() + streams_[stream].past.size();
}

std::vector<ApproximateTimeCore::Set> ApproximateTimeCore::take_sets() {
  std::vector<Set> out;
  out.swap(sets_);
  return out;
}

std::vector<ApproximateTimeCore::Drop> ApproximateTimeCore::take_drops() {
  std::vector<Drop> out;
  out.swap(drops_);
  return out;
}

void ApproximateTimeCore::record_drop(std::size_t i, const Entry& e, DropReason reason) {
  ++streams_[i].stats.dropped[static_cast<std::size_t>(reason)];
  drops_.push_back(Drop{i, e.id, e.stamp, reason});
}

bool ApproximateTimeCore::add(std::size_t stream, double stamp_s, std::uint64_t id) {
  if (stream >= streams_.size())
    fail(ErrorCode::kInvalidArgument, "ApproximateTimeCore::add: stream " + std::to_string(stream) +
                                          " is outside [0, " + std::to_string(streams_.size()) + ")");
  Stream& s = streams_[stream];
  ++s.stats.received;
  if (!std::isfinite(stamp_s)) {
    record_drop(stream, Entry{stamp_s, id}, DropReason::kNonFiniteStamp);
    return false;
  }
  // ROS checks the order only against the messages still held; we check against the last
  // accepted stamp ever, so a late message cannot slip in after its predecessor was emitted.
  if (stamp_s < s.last_stamp) {
    record_drop(stream, Entry{stamp_s, id}, DropReason::kOutOfOrder);
    return false;
  }
  if (std::isfinite(s.last_stamp) && stamp_s - s.last_stamp < s.lower_bound) ++s.stats.bound_violations;
  s.last_stamp = stamp_s;

  s.queue.push_back(Entry{stamp_s, id});
  if (s.queue.size() == 1) {
    ++non_empty_;
    if (non_empty_ == streams_.size()) process();  // every stream has a message now
  }
  // Too many messages held on this stream (process() may leave queue_size + 1 for a moment).
  if (s.queue.size() + s.past.size() > settings_.queue_size) {
    recover_all();  // cancel the ongoing candidate search
    const Entry e = s.queue.front();
    s.queue.pop_front();  // never empties it: it held >= 2 messages (queue_size >= 1)
    record_drop(stream, e, DropReason::kQueueOverflow);
    s.has_dropped = true;
    if (pivot_ != kNoPivot) {
      // The candidate may have contained the dropped message: forget it and start again.
      candidate_.clear();
      pivot_ = kNoPivot;
      process();
    }
  }
  return true;
}

// The oldest (end = false: first index with the minimum) or the latest (end = true: last index
// with the maximum) of the queues' front messages. Assumes every queue is non-empty.
void ApproximateTimeCore::boundary(bool end, std::size_t& index, double& time) const {
  index = 0;
  time = streams_[0].queue.front().stamp;
  for (std::size_t i = 1; i < streams_.size(); ++i) {
    const double t = streams_[i].queue.front().stamp;
    if ((t < time) != end) {
      time = t;
      index = i;
    }
  }
}

// The earliest stamp the next message of stream i can have (for the optimality proof):
// its queue's front, or, for an exhausted queue, max(last examined + lower bound, pivot time).
double ApproximateTimeCore::virtual_time(std::size_t i) const {
  const Stream& s = streams_[i];
  if (!s.queue.empty()) return s.queue.front().stamp;
  // Not empty: the stream's candidate message is at least in "past".
  const double bound = s.past.back().stamp + s.lower_bound;
  return bound > pivot_time_ ? bound : pivot_time_;
}

void ApproximateTimeCore::virtual_boundary(bool end, std::size_t& index, double& time) const {
  index = 0;
  time = virtual_time(0);
  for (std::size_t i = 1; i < streams_.size(); ++i) {
    const double t = virtual_time(i);
    if ((t < time) != end) {
      time = t;
      index = i;
    }
  }
}

void ApproximateTimeCore::move_front_to_past(std::size_t i) {
  Stream& s = streams_[i];
  s.past.push_back(s.queue.front());
  s.queue.pop_front();
  if (s.queue.empty()) --non_empty_;
}

void ApproximateTimeCore::drop_front(std::size_t i, DropReason reason) {
  Stream& s = streams_[i];
  const Entry e = s.queue.front();
  s.queue.pop_front();
  if (s.queue.empty()) --non_empty_;
  record_drop(i, e, reason);
}

// Puts the last `count` examined messages of stream i back at the front of its queue.
void ApproximateTimeCore::recover(std::size_t i, std::size_t count) {
  Stream& s = streams_[i];
  const bool was_empty = s.queue.empty();
  for (; count > 0; --count) {
    s.queue.push_front(s.past.back());
    s.past.pop_back();
  }
  if (was_empty && !s.queue.empty()) ++non_empty_;
}

void ApproximateTimeCore::recover_all() {
  for (std::size_t i = 0; i < streams_.size(); ++i) recover(i, streams_[i].past.size());
}

// The queues' fronts become the candidate. Messages examined before it can never be in a set
// any more: a better candidate starts after them.
void ApproximateTimeCore::make_candidate() {
  candidate_.resize(streams_.size());
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    Stream& s = streams_[i];
    candidate_[i] = s.queue.front();
    for (const Entry& e : s.past) record_drop(i, e, DropReason::kTooOld);
    s.past.clear();
  }
}

// Emits the candidate; the examined messages after it go back to their queues.
void ApproximateTimeCore::publish_candidate() {
  Set set;
  set.ids.resize(streams_.size());
  set.stamps_s.resize(streams_.size());
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    set.ids[i] = candidate_[i].id;
    set.stamps_s[i] = candidate_[i].stamp;
    ++streams_[i].stats.emitted;
  }
  sets_.push_back(std::move(set));
  ++sets_emitted_;
  candidate_.clear();
  pivot_ = kNoPivot;
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    Stream& s = streams_[i];
    const bool was_empty = s.queue.empty();
    while (!s.past.empty()) {
      s.queue.push_front(s.past.back());
      s.past.pop_back();
    }
    // The front is now the candidate's message of this stream (it was the front when the
    // candidate was made, and only messages after it were examined since).
    s.queue.pop_front();
    if (was_empty && !s.queue.empty()) ++non_empty_;
    if (!was_empty && s.queue.empty()) --non_empty_;
  }
}

void ApproximateTimeCore::process() {
  const std::size_t n = streams_.size();
  const double ap1 = 1.0 + settings_.age_penalty;
  while (non_empty_ == n) {
    std::size_t end_index = 0, start_index = 0;
    double end_time = 0.0, start_time = 0.0;
    boundary(true, end_index, end_time);
    boundary(false, start_index, start_time);
    // No dropped message of the other streams could have been better than what they hold, so
    // they can be the pivot again.
    for (std::size_t i = 0; i < n; ++i)
      if (i != end_index) streams_[i].has_dropped = false;
    if (pivot_ == kNoPivot) {
      if (end_time - start_time > settings_.max_interval_duration_s) {
        drop_front(start_index, DropReason::kTooOld);  // no set within the limit can hold it
        continue;
      }
      if (streams_[end_index].has_dropped) {
        // The would-be pivot's stream overflowed: a dropped message might have been the better
        // match, so this oldest message is given up rather than risk a wrong set.
        drop_front(start_index, DropReason::kTooOld);
        continue;
      }
      make_candidate();
      candidate_start_ = start_time;
      candidate_end_ = end_time;
      pivot_ = end_index;
      pivot_time_ = end_time;
      move_front_to_past(start_index);
    } else {
      if ((end_time - candidate_end_) * ap1 >= (start_time - candidate_start_)) {
        move_front_to_past(start_index);  // not better than the candidate
      } else {
        make_candidate();  // better: keep the pivot
        candidate_start_ = start_time;
        candidate_end_ = end_time;
        move_front_to_past(start_index);
      }
    }
    if (start_index == pivot_) {
      publish_candidate();  // every candidate for this pivot has been examined
    } else if ((end_time - candidate_end_) * ap1 >= (pivot_time_ - candidate_start_)) {
      // Provably optimal: every later candidate spans [pivot_time_, end_time], already worse.
      publish_candidate();
    } else if (non_empty_ < n) {
      // Try to prove optimality with the lower bounds on the next messages' stamps.
      std::vector<std::size_t> virtual_moves(n, 0);
      for (;;) {
        std::size_t v_end_index = 0, v_start_index = 0;
        double v_end = 0.0, v_start = 0.0;
        virtual_boundary(true, v_end_index, v_end);
        virtual_boundary(false, v_start_index, v_start);
        if ((v_end - candidate_end_) * ap1 >= (pivot_time_ - candidate_start_)) {
          publish_candidate();  // also undoes the virtual moves
          break;
        }
        if ((v_end - candidate_end_) * ap1 < (v_start - candidate_start_)) {
          // An optimistic future candidate would be better: wait for more messages.
          for (std::size_t i = 0; i < n; ++i) recover(i, virtual_moves[i]);
          break;
        }
        // v_start < pivot_time_ here (else one of the two tests holds), so the queue of
        // v_start_index is not empty.
        move_front_to_past(v_start_index);
        ++virtual_moves[v_start_index];
      }
    }
  }
}

}  // namespace duet
