// segment(): a synthetic room (floor, wall, table top, ceiling, speckle, NaN normals) labelled as
// the header describes; a serial reference on random scenes; floor offset; bad input;
// thread-count independence.
#include "kernel_test_util.hpp"
#include "reference_clustering.hpp"

#include <duet/kernels/error.hpp>
#include <duet/kernels/segmentation.hpp>

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

namespace duet {
namespace test_segmentation {

using test::kNaN;

// ---- reference -----------------------------------------------------------------------------------

std::vector<PointLabel> reference_segment(const std::vector<Eigen::Vector3f>& pts, const std::vector<Eigen::Vector3f>& normals,
                                          const SegmentationSettings& s) {
  std::vector<PointLabel> labels(pts.size(), PointLabel::kIgnored);
  std::vector<std::uint32_t> horizontal;
  for (std::uint32_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3f& p = pts[i];
    const Eigen::Vector3f& n = normals[i];
    if (!is_finite(p) || !is_finite(n)) continue;
    const double h = static_cast<double>(p.z()) - s.floor_z_m;
    if (h < s.min_height_m || h > s.max_height_m) continue;
    const double tilt = std::acos(std::min(1.0, std::abs(static_cast<double>(n.z())) / n.cast<double>().norm())) * 180.0 / std::numbers::pi;
    if (tilt > s.max_floor_tilt_deg) {
      labels[i] = PointLabel::kObstacle;
    } else {
      horizontal.push_back(i);
    }
  }
  const auto clusters = test::reference_clusters(pts, horizontal, s.clustering.tolerance_m, s.clustering.min_size, 0xFFFFFFFFu, false);
  for (const auto& c : clusters) {
    double z = 0.0;
    for (const auto i : c) z += pts[i].z();
    const double centre = z / static_cast<double>(c.size()) - s.floor_z_m;
    for (const auto i : c) labels[i] = centre > s.floor_height_threshold_m ? PointLabel::kObstacle : PointLabel::kFloor;
  }
  return labels;
}

// ---- synthetic room --------------------------------------------------------------------------------

enum class Part { kFloor, kWallLow, kWallHigh, kTable, kCeiling, kNaNNormal, kSpeckleHigh, kSpeckleFloor, kBelow, kTilted30,
                  kTilted10, kNaNPoint, kLowBox };

struct Scene {
  std::vector<Eigen::Vector3f> pts, normals;
  std::vector<Part> part;
  void add(const Eigen::Vector3f& p, const Eigen::Vector3f& n, Part k) {
    pts.push_back(p);
    normals.push_back(n);
    part.push_back(k);
  }
};

Scene make_room(float z0 = 0.0f) {
  Scene s;
  const Eigen::Vector3f up(0, 0, 1);
  const float d = 0.05f;
  const Eigen::Vector3f tilt30 = Eigen::AngleAxisf(30.0f * std::numbers::pi_v<float> / 180.0f, Eigen::Vector3f::UnitX()) * up;
  const Eigen::Vector3f tilt10 = Eigen::AngleAxisf(10.0f * std::numbers::pi_v<float> / 180.0f, Eigen::Vector3f::UnitY()) * up;
  // Floor 4 m x 4 m at z0 with upward normals; a 0.5 m patch with NaN normals, a few points with
  // normals tilted 30 deg (obstacle) or 10 deg (still floor).
  for (int i = 0; i < 80; ++i)
    for (int j = 0; j < 80; ++j) {
      const Eigen::Vector3f p(-2.0f + d * static_cast<float>(i), -2.0f + d * static_cast<float>(j), z0);
      Part k = Part::kFloor;
      Eigen::Vector3f n = up;
      if (i >= 5 && i < 15 && j >= 5 && j < 15) {
        k = Part::kNaNNormal;
        n = Eigen::Vector3f(kNaN, kNaN, kNaN);
      } else if (i == 40 && j % 7 == 0) {
        k = Part::kTilted30;
        n = tilt30;
      } else if (i == 50 && j % 5 == 0) {
        k = Part::kTilted10;
        n = -tilt10;  // a downward normal is as vertical as an upward one
      } else if (i == 60 && j == 60) {
        k = Part::kNaNPoint;
        s.add(Eigen::Vector3f(kNaN, 1.0f, z0), up, k);
        continue;
      }
      s.add(p, n, k);
    }
  // A wall at x = 2.5 up to 2 m with horizontal normals (ignored above max_height 1.2 m).
  for (int j = 0; j < 80; ++j)
    for (int h = 0; h < 40; ++h) {
      const float z = 0.025f + d * static_cast<float>(h);  // no point exactly at max_height_m
      s.add(Eigen::Vector3f(2.5f, -2.0f + d * static_cast<float>(j), z0 + z), Eigen::Vector3f(-1, 0, 0),
            z <= 1.2f ? Part::kWallLow : Part::kWallHigh);
    }
  // A table top at 0.75 m (1.0 x 0.6 m), normals up: an obstacle.
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 12; ++j)
      s.add(Eigen::Vector3f(-1.5f + d * static_cast<float>(i), 0.5f + d * static_cast<float>(j), z0 + 0.75f), up, Part::kTable);
  // A low box top at 5 cm: a horizontal cluster below floor_height_threshold_m, joined to the floor.
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      s.add(Eigen::Vector3f(0.5f + d * static_cast<float>(i), -1.0f + d * static_cast<float>(j), z0 + 0.05f), up, Part::kLowBox);
  // A ceiling at 2.5 m with downward normals: ignored.
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j)
      s.add(Eigen::Vector3f(-2.0f + d * static_cast<float>(i), -2.0f + d * static_cast<float>(j), z0 + 2.5f), -up, Part::kCeiling);
  // Speckle: 8 horizontal points floating at 0.4 m, 10 floor-level points far away (< min_size 20).
  for (int i = 0; i < 8; ++i) s.add(Eigen::Vector3f(1.0f + 0.02f * static_cast<float>(i), 1.0f, z0 + 0.4f), up, Part::kSpeckleHigh);
  for (int i = 0; i < 10; ++i) s.add(Eigen::Vector3f(10.0f + 0.02f * static_cast<float>(i), 10.0f, z0), up, Part::kSpeckleFloor);
  // Points below the floor (a hole / reflection): ignored.
  for (int i = 0; i < 30; ++i) s.add(Eigen::Vector3f(-0.5f + 0.05f * static_cast<float>(i), 1.8f, z0 - 0.5f), up, Part::kBelow);
  return s;
}

PointLabel expected_label(Part k) {
  switch (k) {
    case Part::kFloor:
    case Part::kTilted10:
    case Part::kLowBox:
      return PointLabel::kFloor;
    case Part::kWallLow:
    case Part::kTable:
    case Part::kTilted30:
      return PointLabel::kObstacle;
    default:
      return PointLabel::kIgnored;
  }
}

std::vector<PointLabel> run(const Scene& s, const SegmentationSettings& st) {
  std::vector<PointLabel> labels(s.pts.size(), static_cast<PointLabel>(77));
  segment(s.pts, s.normals, st, labels);
  return labels;
}

// ---- tests -----------------------------------------------------------------------------------------

TEST(Segmentation, SyntheticRoom) {
  for (const float z0 : {0.0f, 1.3f, -0.7f}) {
    const Scene s = make_room(z0);
    SegmentationSettings st;
    st.floor_z_m = z0;
    const auto labels = run(s, st);
    std::map<int, std::size_t> wrong;
    for (std::size_t i = 0; i < s.pts.size(); ++i)
      if (labels[i] != expected_label(s.part[i])) ++wrong[static_cast<int>(s.part[i])];
    for (const auto& [part, count] : wrong) ADD_FAILURE() << "floor at " << z0 << ": " << count << " points of part " << part << " mislabelled";
    EXPECT_EQ(labels, reference_segment(s.pts, s.normals, st));
  }
}

TEST(Segmentation, ThresholdsAreSettings) {
  const Scene s = make_room();
  SegmentationSettings st;
  // Tilt threshold 40 deg: the 30-deg points become floor candidates (and join the floor).
  st.max_floor_tilt_deg = 40.0f;
  auto labels = run(s, st);
  for (std::size_t i = 0; i < s.pts.size(); ++i)
    if (s.part[i] == Part::kTilted30) { EXPECT_EQ(labels[i], PointLabel::kFloor); }
  // Tilt 5 deg: the 10-deg points become obstacles.
  st.max_floor_tilt_deg = 5.0f;
  labels = run(s, st);
  for (std::size_t i = 0; i < s.pts.size(); ++i)
    if (s.part[i] == Part::kTilted10) { EXPECT_EQ(labels[i], PointLabel::kObstacle); }
  // max_height 3 m: the ceiling (horizontal, centre 2.5 m) becomes an obstacle, the whole wall too.
  st = {};
  st.max_height_m = 3.0f;
  labels = run(s, st);
  for (std::size_t i = 0; i < s.pts.size(); ++i) {
    if (s.part[i] == Part::kCeiling || s.part[i] == Part::kWallHigh) { EXPECT_EQ(labels[i], PointLabel::kObstacle); }
  }
  // min_size 5: the 8 floating points become an obstacle, the 10 far floor points floor.
  st = {};
  st.clustering.min_size = 5;
  labels = run(s, st);
  for (std::size_t i = 0; i < s.pts.size(); ++i) {
    if (s.part[i] == Part::kSpeckleHigh) { EXPECT_EQ(labels[i], PointLabel::kObstacle); }
    if (s.part[i] == Part::kSpeckleFloor) { EXPECT_EQ(labels[i], PointLabel::kFloor); }
  }
  // floor_height_threshold 0.8: the table becomes floor.
  st = {};
  st.floor_height_threshold_m = 0.8f;
  labels = run(s, st);
  for (std::size_t i = 0; i < s.pts.size(); ++i)
    if (s.part[i] == Part::kTable) { EXPECT_EQ(labels[i], PointLabel::kFloor); }
  // max_size of the clustering settings does not drop large horizontal surfaces.
  st = {};
  st.clustering.max_size = 100;
  EXPECT_EQ(run(s, st), run(s, {}));
}

TEST(Segmentation, MatchesReferenceOnRandomScenes) {
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-3.0f, 3.0f), h(-0.5f, 1.6f), a(0.0f, 1.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::vector<Eigen::Vector3f> pts, normals;
    const float floor_z = 0.1f * static_cast<float>(seed);
    // Random horizontal slabs at random heights (two at floor level), random points with random normals.
    for (int slab = 0; slab < 12; ++slab) {
      const float z = slab < 2 ? floor_z + 0.02f * static_cast<float>(slab) : h(rng), cx = u(rng), cy = u(rng);
      for (int i = 0; i < 300; ++i) {
        pts.emplace_back(cx + 0.6f * a(rng), cy + 0.6f * a(rng), z + 0.01f * g(rng));
        normals.push_back((Eigen::Vector3f(0, 0, 1) + 0.2f * Eigen::Vector3f(g(rng), g(rng), g(rng))) * (1.0f + a(rng)));
      }
    }
    for (int i = 0; i < 3000; ++i) {
      pts.emplace_back(u(rng), u(rng), h(rng));
      normals.emplace_back(g(rng), g(rng), g(rng));
    }
    for (std::size_t i = 0; i < pts.size(); i += 41) normals[i].x() = kNaN;
    for (std::size_t i = 3; i < pts.size(); i += 53) pts[i].z() = kNaN;
    SegmentationSettings st;
    st.floor_z_m = floor_z;
    st.clustering.tolerance_m = 0.08f;
    st.clustering.min_size = 10;
    std::vector<PointLabel> labels(pts.size());
    segment(pts, normals, st, labels);
    EXPECT_EQ(labels, reference_segment(pts, normals, st)) << "seed " << seed;
    std::size_t counts[3] = {};
    for (const auto l : labels) ++counts[static_cast<int>(l)];
    EXPECT_GT(counts[0], 0u);
    EXPECT_GT(counts[1], 0u);
    EXPECT_GT(counts[2], 0u);
  }
}

TEST(Segmentation, EmptyAndDegenerateInputs) {
  std::vector<PointLabel> none;
  EXPECT_NO_THROW(segment(PointsView(), {}, {}, none));
  const std::vector<Eigen::Vector3f> one{{0, 0, 0}}, up{{0, 0, 1}}, side{{1, 0, 0}}, nan{{kNaN, 0, 0}}, zero{{0, 0, 0}};
  std::vector<PointLabel> l(1);
  segment(one, up, {}, l);
  EXPECT_EQ(l[0], PointLabel::kIgnored);  // a single floor point is speckle (min_size 20)
  segment(one, side, {}, l);
  EXPECT_EQ(l[0], PointLabel::kObstacle);
  segment(one, nan, {}, l);
  EXPECT_EQ(l[0], PointLabel::kIgnored);
  segment(nan, up, {}, l);
  EXPECT_EQ(l[0], PointLabel::kIgnored);
  segment(one, zero, {}, l);  // a zero normal is not a valid normal: ignored or obstacle, never floor
  EXPECT_NE(l[0], PointLabel::kFloor);
  SegmentationSettings st;
  st.clustering.min_size = 1;
  segment(one, up, st, l);
  EXPECT_EQ(l[0], PointLabel::kFloor);
}

TEST(Segmentation, HugeCoordinates) {
  // Points far outside the height band are ignored before clustering; huge horizontal coordinates
  // of floor candidates overflow the clustering grid: kOutOfRange, never a wrong labelling.
  std::vector<Eigen::Vector3f> pts{{0, 0, 1e30f}, {0, 0, -1e30f}, {1, 1, 0}};
  const std::vector<Eigen::Vector3f> up(3, Eigen::Vector3f(0, 0, 1));
  std::vector<PointLabel> l(3);
  SegmentationSettings st;
  st.clustering.min_size = 1;
  segment(pts, up, st, l);
  EXPECT_EQ(l, (std::vector<PointLabel>{PointLabel::kIgnored, PointLabel::kIgnored, PointLabel::kFloor}));
  pts[0] = Eigen::Vector3f(1e30f, 0, 0);
  EXPECT_DUET_ERROR(segment(pts, up, st, l), ErrorCode::kOutOfRange, "too large");
}

TEST(Segmentation, BadInputThrows) {
  const std::vector<Eigen::Vector3f> pts = test::random_points(10, 1), nrm(10, Eigen::Vector3f(0, 0, 1)), short_n(9);
  std::vector<PointLabel> l(10), short_l(3);
  const auto kInv = ErrorCode::kInvalidArgument;
  EXPECT_DUET_ERROR(segment(pts, short_n, {}, l), kInv, "normals");
  EXPECT_DUET_ERROR(segment(pts, nrm, {}, short_l), kInv, "labels");
  SegmentationSettings st;
  st.max_floor_tilt_deg = 91.0f;
  EXPECT_DUET_ERROR(segment(pts, nrm, st, l), kInv, "max_floor_tilt_deg");
  st = {};
  st.floor_z_m = kNaN;
  EXPECT_DUET_ERROR(segment(pts, nrm, st, l), kInv, "floor_z_m");
  st = {};
  st.min_height_m = 2.0f;
  EXPECT_DUET_ERROR(segment(pts, nrm, st, l), kInv, "min_height_m");
  st = {};
  st.floor_height_threshold_m = test::kInf;
  EXPECT_DUET_ERROR(segment(pts, nrm, st, l), kInv, "floor_height_threshold_m");
  st = {};
  st.clustering.tolerance_m = 0.0f;
  EXPECT_DUET_ERROR(segment(pts, nrm, st, l), kInv, "tolerance_m");
}

TEST(Segmentation, IdenticalWithOneAndTwoThreads) {
  Scene s = make_room();
  // Make it bigger: 9 shifted copies of the room.
  const Scene base = s;
  for (int c = 1; c < 9; ++c)
    for (std::size_t i = 0; i < base.pts.size(); ++i)
      s.add(base.pts[i] + Eigen::Vector3f(6.0f * static_cast<float>(c % 3), 6.0f * static_cast<float>(c / 3), 0), base.normals[i], base.part[i]);
  const auto a = test::in_arena(1, [&] { return run(s, {}); });
  const auto b = test::in_arena(2, [&] { return run(s, {}); });
  EXPECT_EQ(a, b);
  EXPECT_EQ(a, reference_segment(s.pts, s.normals, {}));
}

}  // namespace test_segmentation
}  // namespace duet
