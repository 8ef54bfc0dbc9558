// ApproximateTime synchroniser: the emitted sets equal those of a brute-force reference on random
// streams (the pivot rule: among all sets holding the pivot - the latest of the streams' oldest
// messages - the one of least cost (1 + age_penalty) * max - min, oldest among equals), with and
// without inter-message lower bounds; drops counted per stream and reason; bounded queues with a
// silent stream; perfect sync emits at once; payloads are moved, never copied.
#include <duet/kernels/error.hpp>
#include <duet/runtime/robot/synchronizer.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

using duet::ApproximateTimeCore;
using duet::ApproximateTimeSettings;
using duet::ApproximateTimeSync;
using duet::DropReason;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Msg {
  double stamp;
  std::uint64_t id;
};

struct RefResult {
  std::vector<std::vector<std::uint64_t>> sets;
  std::vector<std::uint64_t> dropped;  // per stream ("too old")
  std::vector<std::size_t> remaining;  // per stream, never emitted nor dropped
};

// Brute force over every set holding the pivot, with complete knowledge of all messages.
// Branch and bound on the cost, which only grows as messages are added to a partial set, so
// the result is the exact minimum; the enumeration is lexicographic (older messages first) and
// only a strictly smaller cost replaces the best, so among equal costs the oldest set wins.
RefResult reference(const std::vector<std::vector<Msg>>& streams, double max_interval, double age_penalty) {
  const std::size_t n = streams.size();
  RefResult r;
  r.dropped.assign(n, 0);
  std::vector<std::size_t> head(n, 0);
  const double ap1 = 1.0 + age_penalty;
  for (;;) {
    bool exhausted = false;
    for (std::size_t j = 0; j < n; ++j) exhausted |= head[j] >= streams[j].size();
    if (exhausted) break;
    std::size_t end_i = 0, start_i = 0;
    for (std::size_t j = 1; j < n; ++j) {
      if (streams[j][head[j]].stamp >= streams[end_i][head[end_i]].stamp) end_i = j;
      if (streams[j][head[j]].stamp < streams[start_i][head[start_i]].stamp) start_i = j;
    }
    const double end_t = streams[end_i][head[end_i]].stamp, start_t = streams[start_i][head[start_i]].stamp;
    if (end_t - start_t > max_interval) {
      ++head[start_i];
      ++r.dropped[start_i];
      continue;
    }
    std::vector<std::size_t> pick(n), best;
    double best_cost = kInf;
    // Recursive enumeration over streams 0..n-1; the pivot's stream is fixed to its head.
    auto rec = [&](auto&& self, std::size_t j, double mn, double mx) -> void {
      if (j == n) {
        const double cost = ap1 * mx - mn;
        if (cost < best_cost) {
          best_cost = cost;
          best = pick;
        }
        return;
      }
      const std::size_t lo = head[j], hi = j == end_i ? head[j] + 1 : streams[j].size();
      for (std::size_t k = lo; k < hi; ++k) {
        const double t = streams[j][k].stamp;
        const double mn2 = std::min(mn, t), mx2 = std::max(mx, t);
        if (ap1 * mx2 - mn2 >= best_cost) {
          if (t >= mx) break;  // later messages only raise the cost further
          continue;
        }
        pick[j] = k;
        self(self, j + 1, mn2, mx2);
      }
    };
    rec(rec, 0, kInf, -kInf);
    std::vector<std::uint64_t> set(n);
    for (std::size_t j = 0; j < n; ++j) {
      set[j] = streams[j][best[j]].id;
      r.dropped[j] += best[j] - head[j];
      head[j] = best[j] + 1;
    }
    r.sets.push_back(std::move(set));
  }
  for (std::size_t j = 0; j < n; ++j) r.remaining.push_back(streams[j].size() - head[j]);
  return r;
}

struct Arrival {
  double time;
  std::size_t stream;
  Msg msg;
};

// Random streams: per stream a rate in [5, 40] Hz, a phase, +-30 % jitter of the period, 15 %
// of the messages lost; each message arrives after a random latency, in order within its
// stream. The last message of every stream is a sentinel far in the future (all equal), so the
// online synchroniser can decide every set that holds a real message.
struct Scenario {
  std::vector<std::vector<Msg>> streams;
  std::vector<Arrival> arrivals;
};

Scenario random_scenario(std::mt19937_64& rng, std::size_t n, double duration) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Scenario sc;
  sc.streams.resize(n);
  std::uint64_t next_id = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const double period = 1.0 / (5.0 + 35.0 * u(rng));
    double arrival = 0.0;
    for (double t = u(rng) * period; t < duration; t += period) {
      const double stamp = t + (u(rng) - 0.5) * 0.6 * period;
      if (u(rng) < 0.15) continue;
      const Msg m{stamp, next_id++};
      sc.streams[j].push_back(m);
      arrival = std::max(arrival, stamp + 0.05 * u(rng));
      sc.arrivals.push_back({arrival, j, m});
    }
  }
  std::stable_sort(sc.arrivals.begin(), sc.arrivals.end(),
                   [](const Arrival& a, const Arrival& b) { return a.time < b.time; });
  for (std::size_t j = 0; j < n; ++j) {
    const Msg m{duration + 100.0, next_id++};
    sc.streams[j].push_back(m);
    sc.arrivals.push_back({duration + 200.0, j, m});
  }
  return sc;
}

// Feeds the arrivals; returns the sets and, per set, the index of the add() that emitted it.
struct Online {
  std::vector<std::vector<std::uint64_t>> sets;
  std::vector<std::size_t> emitted_at;
};
Online run_online(ApproximateTimeCore& sync, const std::vector<Arrival>& arrivals) {
  Online o;
  for (std::size_t a = 0; a < arrivals.size(); ++a) {
    EXPECT_TRUE(sync.add(arrivals[a].stream, arrivals[a].msg.stamp, arrivals[a].msg.id));
    for (auto& s : sync.take_sets()) {
      o.sets.push_back(s.ids);
      o.emitted_at.push_back(a);
    }
    (void)sync.take_drops();
  }
  return o;
}

void expect_invariant(const ApproximateTimeCore& sync) {
  for (std::size_t j = 0; j < sync.num_streams(); ++j) {
    const auto& st = sync.stats(j);
    EXPECT_EQ(st.received, st.emitted + st.dropped_total() + sync.pending(j)) << "stream " << j;
  }
}

}  // namespace

TEST(Synchronizer, MatchesBruteForceReferenceOnRandomStreams) {
  std::mt19937_64 rng(20240611);
  const double intervals[] = {kInf, 0.05, 0.02};
  const double penalties[] = {0.0, 0.1, 0.7};
  std::size_t total_sets = 0, total_too_old = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t n = 2 + static_cast<std::size_t>(trial % 3);
    const Scenario sc = random_scenario(rng, n, n == 4 ? 4.0 : 8.0);
    ApproximateTimeSettings s;
    s.queue_size = 1000000;  // no overflow: the reference has unbounded queues
    s.max_interval_duration_s = intervals[trial % 3 == 0 ? (trial / 3) % 3 : (trial / 7) % 3];
    s.age_penalty = penalties[(trial / 2) % 3];
    ApproximateTimeCore sync(n, s);
    const Online got = run_online(sync, sc.arrivals);
    const RefResult want = reference(sc.streams, s.max_interval_duration_s, s.age_penalty);
    ASSERT_EQ(got.sets, want.sets) << "trial " << trial << " n " << n << " max_interval "
                                   << s.max_interval_duration_s << " age_penalty " << s.age_penalty;
    for (std::size_t j = 0; j < n; ++j) {
      const auto& st = sync.stats(j);
      EXPECT_EQ(st.dropped_by(DropReason::kTooOld), want.dropped[j]) << "trial " << trial << " stream " << j;
      EXPECT_EQ(st.dropped_by(DropReason::kQueueOverflow), 0u);
      EXPECT_EQ(st.dropped_by(DropReason::kOutOfOrder), 0u);
      EXPECT_EQ(sync.pending(j), want.remaining[j]) << "trial " << trial << " stream " << j;
      EXPECT_EQ(st.emitted, want.sets.size());
      total_too_old += want.dropped[j];
    }
    expect_invariant(sync);
    total_sets += want.sets.size();
  }
  // The scenarios exercise the interesting paths: many sets and many unmatched messages.
  std::printf("reference: %zu sets, %zu messages too old\n", total_sets, total_too_old);
  EXPECT_GT(total_sets, 3000u);
  EXPECT_GT(total_too_old, 8000u);
}

TEST(Synchronizer, LowerBoundsGiveTheSameSetsAndNeverLater) {
  std::mt19937_64 rng(77);
  std::size_t earlier = 0, compared = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const std::size_t n = 2 + static_cast<std::size_t>(trial % 3);
    const Scenario sc = random_scenario(rng, n, 6.0);
    ApproximateTimeSettings s;
    s.queue_size = 1000000;
    s.max_interval_duration_s = trial % 2 ? kInf : 0.05;
    s.age_penalty = 0.1;
    ApproximateTimeCore plain(n, s);
    // True lower bounds: the smallest gap of each stream (the sentinel gap is larger).
    for (std::size_t j = 0; j < n; ++j) {
      double gap = kInf;
      for (std::size_t k = 1; k < sc.streams[j].size(); ++k)
        gap = std::min(gap, sc.streams[j][k].stamp - sc.streams[j][k - 1].stamp);
      s.inter_message_lower_bounds_s.push_back(std::isfinite(gap) ? std::max(gap, 0.0) : 0.0);
    }
    ApproximateTimeCore bounded(n, s);
    const Online a = run_online(plain, sc.arrivals);
    const Online b = run_online(bounded, sc.arrivals);
    ASSERT_EQ(a.sets, b.sets) << "trial " << trial;
    for (std::size_t k = 0; k < a.sets.size(); ++k) {
      EXPECT_LE(b.emitted_at[k], a.emitted_at[k]) << "trial " << trial << " set " << k;
      earlier += b.emitted_at[k] < a.emitted_at[k];
      ++compared;
    }
    for (std::size_t j = 0; j < n; ++j) EXPECT_EQ(bounded.stats(j).bound_violations, 0u);
  }
  EXPECT_GT(earlier, compared / 10) << "the bounds should let many sets out earlier";
}

TEST(Synchronizer, PerfectSyncEmitsOnTheMessageThatCompletesTheSet) {
  ApproximateTimeCore sync(3);
  for (int k = 0; k < 30; ++k) {
    const double t = k / 30.0;
    for (std::size_t j = 0; j < 3; ++j) {
      EXPECT_TRUE(sync.add(j, t, static_cast<std::uint64_t>(k * 3 + static_cast<int>(j))));
      const auto sets = sync.take_sets();
      if (j < 2) {
        EXPECT_TRUE(sets.empty()) << "k " << k << " j " << j;
      } else {
        ASSERT_EQ(sets.size(), 1u) << "k " << k;
        for (std::size_t i = 0; i < 3; ++i) {
          EXPECT_EQ(sets[0].ids[i], static_cast<std::uint64_t>(k * 3 + static_cast<int>(i)));
          EXPECT_EQ(sets[0].stamps_s[i], t);
        }
      }
    }
  }
  for (std::size_t j = 0; j < 3; ++j) {
    EXPECT_EQ(sync.stats(j).dropped_total(), 0u);
    EXPECT_EQ(sync.stats(j).emitted, 30u);
    EXPECT_EQ(sync.pending(j), 0u);
  }
  EXPECT_TRUE(sync.take_drops().empty());
}

TEST(Synchronizer, OutOfOrderAndNonFiniteStampsAreDroppedAndCounted) {
  ApproximateTimeCore sync(2);
  EXPECT_TRUE(sync.add(0, 1.0, 10));
  EXPECT_FALSE(sync.add(0, 0.5, 11));                                         // older than 1.0
  EXPECT_FALSE(sync.add(0, std::numeric_limits<double>::quiet_NaN(), 12));
  EXPECT_FALSE(sync.add(0, kInf, 13));
  EXPECT_FALSE(sync.add(1, -kInf, 14));
  EXPECT_TRUE(sync.add(0, 1.0, 15));  // an equal stamp is in order (as in ROS)
  const auto drops = sync.take_drops();
  ASSERT_EQ(drops.size(), 4u);
  EXPECT_EQ(drops[0].id, 11u);
  EXPECT_EQ(drops[0].reason, DropReason::kOutOfOrder);
  EXPECT_EQ(drops[1].reason, DropReason::kNonFiniteStamp);
  EXPECT_EQ(drops[2].reason, DropReason::kNonFiniteStamp);
  EXPECT_EQ(drops[3].stream, 1u);
  EXPECT_EQ(drops[3].reason, DropReason::kNonFiniteStamp);
  EXPECT_EQ(sync.stats(0).dropped_by(DropReason::kOutOfOrder), 1u);
  EXPECT_EQ(sync.stats(0).dropped_by(DropReason::kNonFiniteStamp), 2u);
  EXPECT_EQ(sync.stats(1).dropped_by(DropReason::kNonFiniteStamp), 1u);
  EXPECT_TRUE(sync.take_sets().empty());
  // A refused message does not disturb the rest: stream 1 at 1.0 pairs with the first 1.0.
  EXPECT_TRUE(sync.add(1, 1.0, 20));
  auto sets = sync.take_sets();
  ASSERT_EQ(sets.size(), 1u);
  EXPECT_EQ(sets[0].ids, (std::vector<std::uint64_t>{10, 20}));
  EXPECT_EQ(sync.pending(0), 1u);  // the second 1.0 waits
  // After a set was emitted, a message older than it is still out of order (ROS would take it).
  EXPECT_FALSE(sync.add(1, 0.9, 21));
  EXPECT_EQ(sync.stats(1).dropped_by(DropReason::kOutOfOrder), 1u);
  expect_invariant(sync);
  EXPECT_STREQ(duet::to_string(DropReason::kQueueOverflow), "queue overflow");
}

TEST(Synchronizer, EmptyStreamsEmitNothing) {
  ApproximateTimeCore sync(4);
  EXPECT_TRUE(sync.take_sets().empty());
  EXPECT_TRUE(sync.take_drops().empty());
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_EQ(sync.pending(j), 0u);
    EXPECT_EQ(sync.stats(j).received, 0u);
  }
  EXPECT_EQ(sync.sets_emitted(), 0u);
  ApproximateTimeSync<int> typed(2);
  EXPECT_FALSE(typed.has_set());
  EXPECT_FALSE(typed.pop().has_value());
  EXPECT_TRUE(typed.take_sets().empty());
}

TEST(Synchronizer, SilentStreamKeepsQueuesBoundedAndCountsOverflow) {
  ApproximateTimeSettings s;
  s.queue_size = 10;
  ApproximateTimeCore sync(3, s);
  for (int k = 0; k < 1000; ++k) {
    const double t = k * 0.02;
    sync.add(0, t, static_cast<std::uint64_t>(2 * k));
    sync.add(1, t + 0.001, static_cast<std::uint64_t>(2 * k + 1));
    EXPECT_LE(sync.pending(0), 10u);
    EXPECT_LE(sync.pending(1), 10u);
  }
  EXPECT_TRUE(sync.take_sets().empty());
  EXPECT_EQ(sync.pending(0), 10u);
  EXPECT_EQ(sync.pending(1), 10u);
  EXPECT_EQ(sync.stats(0).dropped_by(DropReason::kQueueOverflow), 990u);
  EXPECT_EQ(sync.stats(1).dropped_by(DropReason::kQueueOverflow), 990u);
  EXPECT_EQ(sync.take_drops().size(), 1980u);
  expect_invariant(sync);
  // The silent stream wakes up: the old messages it cannot match go as too old; the newest pair
  // matches it once the next message of stream 0 proves that no later one can do better (it
  // could have come at 19.9805 s).
  const double last = 999 * 0.02;
  sync.add(2, last + 0.0005, 5000);
  EXPECT_TRUE(sync.take_sets().empty());
  EXPECT_EQ(sync.pending(2), 1u);
  sync.add(0, last + 0.02, 6000);
  const auto sets = sync.take_sets();
  ASSERT_EQ(sets.size(), 1u);
  EXPECT_EQ(sets[0].ids, (std::vector<std::uint64_t>{1998, 1999, 5000}));
  EXPECT_EQ(sync.stats(0).dropped_by(DropReason::kTooOld), 9u);
  EXPECT_EQ(sync.stats(1).dropped_by(DropReason::kTooOld), 9u);
  expect_invariant(sync);
}

TEST(Synchronizer, MaxIntervalDurationRejectsSetsTooSpread) {
  for (const double offset : {0.02, 0.03}) {
    ApproximateTimeCore sync(2);  // default max_interval_duration_s = 0.025
    for (int k = 0; k < 50; ++k) {
      sync.add(0, k * 0.1, static_cast<std::uint64_t>(k));
      sync.add(1, k * 0.1 + offset, static_cast<std::uint64_t>(100 + k));
    }
    const auto sets = sync.take_sets();
    if (offset < 0.025) {
      ASSERT_EQ(sets.size(), 49u);  // the last pair waits for proof
      for (const auto& set : sets) EXPECT_NEAR(set.stamps_s[1] - set.stamps_s[0], offset, 1e-12);
      EXPECT_EQ(sync.stats(0).dropped_total() + sync.stats(1).dropped_total(), 0u);
    } else {
      EXPECT_TRUE(sets.empty());
      EXPECT_EQ(sync.stats(0).dropped_by(DropReason::kTooOld), 50u);
      EXPECT_EQ(sync.stats(1).dropped_by(DropReason::kTooOld), 49u);
    }
    expect_invariant(sync);
  }
}

// The runtime's use: two cameras at 30 Hz rendered at the same instants and odometry at 50 Hz,
// pushed in stamp order (odometry first at equal stamps). Every frame pair is matched with the
// odometry message the cost prefers: the one before it unless the one after is closer by the
// age penalty's margin (cost 0.1 t + a for odometry a before, 0.1 t + 1.1 b for b after).
TEST(Synchronizer, DualCameraAndOdometryPairsEveryFrame) {
  ApproximateTimeSync<int> sync(3);
  struct In {
    double t;
    std::size_t stream;
    int payload;
  };
  std::vector<In> in;
  const int frames = 300, odoms = 500;  // 10 s
  for (int k = 0; k < odoms; ++k) in.push_back({k / 50.0, 2, k});
  for (int k = 0; k < frames; ++k) {
    in.push_back({k / 30.0, 0, k});
    in.push_back({k / 30.0, 1, k});
  }
  std::stable_sort(in.begin(), in.end(), [](const In& a, const In& b) {
    return std::tie(a.t, b.stream) < std::tie(b.t, a.stream);  // at equal t: odometry first
  });
  for (const auto& m : in) sync.add(m.stream, m.t, m.payload);
  const auto sets = sync.take_sets();
  ASSERT_GE(sets.size(), static_cast<std::size_t>(frames - 1));
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const auto& s = sets[k];
    ASSERT_EQ(s.messages.size(), 3u);
    EXPECT_EQ(s.messages[0].payload, static_cast<int>(k));
    EXPECT_EQ(s.messages[1].payload, static_cast<int>(k));
    const double t = s.messages[0].stamp_s;
    EXPECT_EQ(s.messages[1].stamp_s, t);
    // The preferred odometry message by the cost.
    const int before = static_cast<int>(std::floor(t * 50.0 + 1e-9));
    const double a = t - before / 50.0, b = (before + 1) / 50.0 - t;
    const int want = a <= 1e-12 || a < 1.1 * b ? before : before + 1;
    EXPECT_EQ(s.messages[2].payload, want) << "frame " << k;
    EXPECT_LE(s.max_stamp_s() - s.min_stamp_s(), 0.01 + 1e-12);
  }
  EXPECT_EQ(sync.stats(0).dropped_total(), 0u);
  EXPECT_EQ(sync.stats(1).dropped_total(), 0u);
  EXPECT_GT(sync.stats(2).dropped_by(DropReason::kTooOld), 150u);  // 50 Hz vs 30 Hz
}

TEST(Synchronizer, RandomStressKeepsInvariantsWithSmallQueues) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t n = 2 + static_cast<std::size_t>(trial % 4);
    ApproximateTimeSettings s;
    s.queue_size = 1 + static_cast<std::size_t>(trial % 5);
    s.max_interval_duration_s = trial % 2 ? 0.03 : kInf;
    ApproximateTimeCore sync(n, s);
    std::vector<double> last(n, 0.0);
    std::vector<std::int64_t> last_emitted(n, -1);
    std::uint64_t id = 0;
    double now = 0.0;
    for (int k = 0; k < 3000; ++k) {
      // Streams in random order around a common time, with jitter and bursts.
      now += 0.01 * u(rng);
      const std::size_t j = static_cast<std::size_t>(u(rng) * static_cast<double>(n)) % n;
      double t = std::max(last[j], now + 0.02 * (u(rng) - 0.5));
      if (u(rng) < 0.01) t = last[j] - 0.1;                                      // out of order
      if (u(rng) < 0.005) t = std::numeric_limits<double>::quiet_NaN();         // broken stamp
      if (sync.add(j, t, id++)) last[j] = t;
      EXPECT_LE(sync.pending(j), s.queue_size);
      for (const auto& set : sync.take_sets()) {
        double mn = kInf, mx = -kInf;
        for (std::size_t i = 0; i < n; ++i) {
          // ids grow with the add() order, so per stream they must grow from set to set.
          EXPECT_GT(static_cast<std::int64_t>(set.ids[i]), last_emitted[i]) << "sets must not cross";
          last_emitted[i] = static_cast<std::int64_t>(set.ids[i]);
          mn = std::min(mn, set.stamps_s[i]);
          mx = std::max(mx, set.stamps_s[i]);
        }
        EXPECT_LE(mx - mn, s.max_interval_duration_s);
      }
      (void)sync.take_drops();
    }
    expect_invariant(sync);
    std::uint64_t refused = 0;
    for (std::size_t j = 0; j < n; ++j)
      refused += sync.stats(j).dropped_by(DropReason::kOutOfOrder) + sync.stats(j).dropped_by(DropReason::kNonFiniteStamp);
    EXPECT_GT(refused, 0u);
    if (s.queue_size >= 2) {
      EXPECT_GT(sync.sets_emitted(), 20u) << "trial " << trial;
    }
  }
}

namespace {
struct Counted {
  static inline int copies = 0;
  static inline int live = 0;
  int value = 0;
  explicit Counted(int v) : value(v) { ++live; }
  Counted(const Counted& o) : value(o.value) {
    ++copies;
    ++live;
  }
  Counted(Counted&& o) noexcept : value(o.value) { ++live; }
  Counted& operator=(const Counted& o) {
    value = o.value;
    ++copies;
    return *this;
  }
  Counted& operator=(Counted&& o) noexcept {
    value = o.value;
    return *this;
  }
  ~Counted() { --live; }
};
}  // namespace

TEST(Synchronizer, PayloadsAreMovedNeverCopiedAndDroppedOnesDestroyed) {
  Counted::copies = 0;
  Counted::live = 0;
  {
    ApproximateTimeSync<Counted> sync(2);
    std::vector<ApproximateTimeCore::Drop> dropped;
    sync.set_drop_callback([&](const ApproximateTimeCore::Drop& d) { dropped.push_back(d); });
    sync.add(0, 0.0, Counted(1));
    sync.add(0, 0.1, Counted(2));
    EXPECT_FALSE(sync.add(0, 0.05, Counted(3)));  // out of order: destroyed at once
    EXPECT_EQ(Counted::live, 2);
    sync.add(1, 0.1, Counted(4));  // pairs with 0.1; 0.0 is too old
    auto s = sync.pop();
    ASSERT_TRUE(s.has_value());
    EXPECT_EQ(s->messages[0].payload.value, 2);
    EXPECT_EQ(s->messages[1].payload.value, 4);
    EXPECT_EQ(Counted::live, 2);  // only the set's two payloads are alive
    ASSERT_EQ(dropped.size(), 2u);
    EXPECT_EQ(dropped[0].reason, DropReason::kOutOfOrder);
    EXPECT_EQ(dropped[1].reason, DropReason::kTooOld);
    EXPECT_EQ(dropped[1].stamp_s, 0.0);
    // Slots are reused: many more messages, still no copies.
    for (int k = 0; k < 100; ++k) {
      sync.add(0, 1.0 + k, Counted(k));
      sync.add(1, 1.0 + k, Counted(k));
    }
    EXPECT_EQ(sync.take_sets().size(), 100u);
  }
  EXPECT_EQ(Counted::copies, 0);
  EXPECT_EQ(Counted::live, 0);

  // A move-only payload compiles and goes through.
  ApproximateTimeSync<std::unique_ptr<int>> sync(2);
  sync.add(0, 1.0, std::make_unique<int>(7));
  sync.add(1, 1.0, std::make_unique<int>(8));
  auto sets = sync.take_sets();
  ASSERT_EQ(sets.size(), 1u);
  EXPECT_EQ(*sets[0].messages[0].payload, 7);
  EXPECT_EQ(*sets[0].messages[1].payload, 8);
}

TEST(Synchronizer, InvalidSettingsAndArgumentsThrow) {
  auto expect_invalid = [](auto&& f, const std::string& part) {
    try {
      f();
      ADD_FAILURE() << "no error, expected one naming " << part;
    } catch (const duet::Error& e) {
      EXPECT_EQ(e.code(), duet::ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  auto with = [](auto change) {
    ApproximateTimeSettings s;
    change(s);
    return s;
  };
  expect_invalid([] { ApproximateTimeCore c(1); }, "num_streams");
  expect_invalid([] { ApproximateTimeCore c(65); }, "num_streams");
  expect_invalid([&] { ApproximateTimeCore c(2, with([](auto& s) { s.queue_size = 0; })); }, "queue_size");
  expect_invalid([&] { ApproximateTimeCore c(2, with([](auto& s) { s.max_interval_duration_s = -0.1; })); },
                 "max_interval_duration_s");
  expect_invalid(
      [&] { ApproximateTimeCore c(2, with([](auto& s) { s.max_interval_duration_s = std::nan(""); })); },
      "max_interval_duration_s");
  expect_invalid([&] { ApproximateTimeCore c(2, with([](auto& s) { s.age_penalty = -0.5; })); }, "age_penalty");
  expect_invalid([&] { ApproximateTimeCore c(2, with([](auto& s) { s.age_penalty = kInf; })); }, "age_penalty");
  expect_invalid(
      [&] { ApproximateTimeCore c(2, with([](auto& s) { s.inter_message_lower_bounds_s = {0.0, -1.0}; })); },
      "inter_message_lower_bounds_s[1]");
  expect_invalid(
      [&] { ApproximateTimeCore c(2, with([](auto& s) { s.inter_message_lower_bounds_s = {0.0, kInf}; })); },
      "inter_message_lower_bounds_s[1]");
  expect_invalid([&] { ApproximateTimeCore c(3, with([](auto& s) { s.inter_message_lower_bounds_s = {0.0}; })); },
                 "inter_message_lower_bounds_s");
  ApproximateTimeCore c(2);
  expect_invalid([&] { c.add(2, 0.0, 0); }, "stream 2");
  expect_invalid([&] { (void)c.stats(5); }, "stream 5");
  expect_invalid([&] { (void)c.pending(2); }, "stream 2");
  ApproximateTimeSync<std::unique_ptr<int>> typed(2);
  expect_invalid([&] { typed.add(3, 0.0, std::make_unique<int>(1)); }, "stream 3");
  EXPECT_EQ(typed.stats(0).received, 0u);
  // max_interval_duration_s = inf (ROS's default) and age_penalty = 0 are valid.
  EXPECT_NO_THROW(ApproximateTimeCore(2, with([](auto& s) {
                    s.max_interval_duration_s = kInf;
                    s.age_penalty = 0.0;
                  })));
}
