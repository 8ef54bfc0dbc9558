#pragma once
/// @file renderer.hpp
/// Simulated RGB-D sensors (issue 4, part 2): a World is turned into a triangle mesh once, put
/// in an Embree scene, and every frame of a sensor is ray traced from it - a 16-bit depth image
/// with a Kinect-like noise model and an 8-bit RGB image registered to it (same pixels).
///
/// Camera model: the pinhole model of back_projection.hpp. A pixel (u, v) (integer coordinates
/// at pixel centres, the convention of PinholeIntrinsics with cx = (w-1)/2) looks along
/// d_optical = ((u - cx) / fx, (v - cy) / fy, 1) in the optical frame (z forward, x right,
/// y down). The depth of a pixel is the optical-frame z of the hit (not the ray length), so
/// duet::back_project() of a noise-free image returns points on the world's surfaces.
///
/// Depth image: raw units of SensorProfile::depth_units_per_m (round to nearest), 0 = no return
/// (nothing hit, out of [min_depth_m, max_depth_m], grazing incidence, random dropout, or a
/// value that does not fit 16 bits).
/// Colour image: RGB (not BGR), 3 bytes per pixel, row-major; pixels that see nothing are black.
///
/// Frames: the world frame is z up, floor at z = 0, SI units (DESIGN.md §6).
///
/// Determinism: every random draw (depth noise, dropout) is a counter-based hash of
/// (frame_seed, pixel index); nothing is drawn from a shared generator, so an image depends
/// only on (world, settings, sensor, pose, frame_seed) - never on the thread count, the tile
/// order or earlier frames. Callers should give each sensor and each frame its own seed.
#include <duet/kernels/back_projection.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/sim/world.hpp>

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace duet::sim {

/// Depth noise of a first-generation Kinect (structured light), applied to the true optical-frame
/// depth z [m] of every hit, in this order:
///  1. incidence: the angle theta between the ray and the surface normal above
///     max_incidence_deg gives no return (the projected speckle pattern is too stretched;
///     Nguyen et al. 2012 measure up to about 70-80 deg, beyond which returns are lost);
///  2. axial noise: z += sigma(z, theta) * N(0, 1) with (Nguyen, Izadi & Lovell 2012, Eq. 6/7)
///        sigma(z, theta) = a + b * (z - c)^2 + angular_m * theta^2 / (sqrt(z) * (pi/2 - theta)^2);
///  3. disparity quantisation (Khoshelham & Elberink 2012, §3.2): the Kinect measures disparity
///     in 1/8 pixel steps, so depth comes in steps of z^2 / (f * b * 8) = q * z^2 with
///     f = 580 px, b = 0.075 m: q ~ 2.87e-3 /m. Implemented by rounding the inverse depth 1/z
///     to a multiple of q (exact steps q * z^2 to first order);
///  4. range: a measured depth outside the sensor's [min_depth_m, max_depth_m] gives 0;
///  5. random dropout: each pixel independently loses its return with probability dropout_rate;
///  6. the raw value is round(z * depth_units_per_m).
/// With enabled = false the depth is exact (true z, rounded to the raw unit) and only the range
/// check (4) and the 16-bit limit remain - for tests and ground truth.
struct KinectNoiseSettings {
  bool enabled = true;               ///< false: noise-free depth (range check and rounding only)
  /// Axial noise constant term [m], [0, 1]. Nguyen et al. 2012: 0.0012 m.
  float axial_a_m = 0.0012f;
  /// Axial noise quadratic coefficient [1/m] (sigma grows as b * (z - c)^2), [0, 1].
  /// Nguyen et al. 2012: 0.0019 /m.
  float axial_b_per_m = 0.0019f;
  /// Depth where the quadratic term is zero [m], [0, 10]. Nguyen et al. 2012: 0.4 m.
  float axial_c_m = 0.4f;
  /// Angular term coefficient [m^1.5] of Nguyen et al. 2012 (0.0001 m^1.5 / sqrt(z) scaled by
  /// theta^2 / (pi/2 - theta)^2), [0, 1]. 0 disables it.
  float axial_angular_m = 0.0001f;
  /// Disparity quantisation q [1/m]: depth steps of q * z^2, [0, 1]; 0 disables quantisation.
  /// Khoshelham & Elberink 2012: 1 / (580 px * 0.075 m * 8) = 2.87e-3; we use 2.85e-3.
  float quantisation_per_m = 2.85e-3f;
  /// Incidence angle above which a pixel has no return [deg], (0, 90]. 80 deg (Nguyen et al.
  /// 2012 report failing returns from 70-80 deg on); a sensor 0.27 m above the floor then
  /// still sees the floor up to 1.5 m away.
  float max_incidence_deg = 80.0f;
  /// Probability [0, 1] that a pixel loses its return (isolated holes of the speckle
  /// matching). 0.005: a tuning choice (no paper value), small enough not to matter for mapping.
  float dropout_rate = 0.005f;
};

/// Throws duet::Error(kInvalidArgument) naming the field and its allowed range.
void validate(const KinectNoiseSettings& settings);

/// Rendering settings. Colour: the surface colour times its procedural texture (evaluated in
/// world coordinates on the surface's plane, so a point looks the same from every view) times a
/// Lambert term from one fixed directional light plus ambient:
///   shade = ambient + (1 - ambient) * max(0, n . l)   (n: the normal facing the camera).
struct RenderSettings {
  KinectNoiseSettings noise;
  /// Direction towards the light in the world frame (normalised internally), non-zero and
  /// finite. Default: from above, slightly from +x/+y so that walls facing different ways get
  /// different brightness (as in a room lit by ceiling lights and windows).
  Eigen::Vector3f light_direction{0.35f, 0.55f, 1.0f};
  /// Ambient fraction of the brightness, [0, 1]. 0.45 keeps walls facing away from the light
  /// textured (ORB needs contrast everywhere).
  float ambient = 0.45f;
  /// Ray-triangle intersection. false (default): Embree's fast mode on triangles each grown in
  /// its plane by 0.02 mm + 5e-7 x the world's largest coordinate (0.026 mm in the lab), so
  /// that neighbouring triangles overlap and rays do not slip through shared edges. Silhouettes
  /// move by that margin, so a ray passing that close to an edge may see the other surface:
  /// against the robust mode over 600 noise-free frames (184 M pixels) from random free poses,
  /// the depth differs by more than 1 cm at 2 pixels per frame in the lab and 13 in the Willow
  /// Garage map (silhouette pixels; tests/runtime/test_sim_renderer.cpp checks that such
  /// pixels lie on depth discontinuities), and 1-2 returns per frame are lost or gained.
  /// true: Embree's robust mode on the exact triangles, about 1.6x the ray cost (the rays are
  /// about half of a frame's time).
  bool robust_intersection = false;
};

/// Throws duet::Error(kInvalidArgument) naming the field and its allowed range.
void validate(const RenderSettings& settings);

/// The world as triangles (built once per world).
///  - every Solid: one quad (2 triangles) per polygon edge, the top cap, and the bottom cap when
///    z_min_m > 0 (a cap at or below the floor is never visible); caps by ear clipping;
///  - the floor rectangle at z = 0 (normal +z) and, when ceiling_height_m > 0, the ceiling
///    (normal -z) over the same rectangle.
/// Winding: counter-clockwise seen from outside, so (b - a) x (c - a) is the outward normal.
struct WorldMesh {
  std::vector<Eigen::Vector3f> vertices;                  ///< world frame [m]
  std::vector<std::array<std::uint32_t, 3>> triangles;    ///< indices into vertices
  /// Per triangle: index into `surfaces`.
  std::vector<std::uint32_t> triangle_surface;
  /// Surfaces: [0] the floor, [1] the ceiling (present even without a ceiling), [2 + i] solid i.
  std::vector<Surface> surfaces;
};

/// Builds the mesh of a world (validate() it first: polygons must be simple and CCW).
/// Throws duet::Error(kInvalidArgument) if the floor is empty or an ear cannot be clipped
/// (a polygon that is not simple).
[[nodiscard]] WorldMesh build_world_mesh(const World& world);

/// One rendered RGB-D frame. Buffers are reused across render() calls (no reallocation when
/// the size does not change).
using RgbdImage = duet::RgbdImage;  // robot_io.hpp

using duet::frame_view;  // robot_io.hpp

/// One frame for RgbdRenderer::render_batch(): the arguments of render() / render_depth_only().
/// The pointers are not owned and must stay valid during the call.
struct RenderJob {
  const SensorProfile* sensor = nullptr;  ///< intrinsics, depth range and units
  /// Sensor pose: optical frame -> world frame [m].
  Eigen::Isometry3f T_world_optical = Eigen::Isometry3f::Identity();
  std::uint64_t frame_seed = 0;  ///< noise seed of this frame
  RgbdImage* out = nullptr;      ///< resized to the sensor's image size; one per job
  bool colour = true;            ///< false: depth only, as render_depth_only()
};

/// Ray-traces RGB-D frames of a World with Embree.
///
/// Thread safety: construction is not thread safe with respect to the same object; after it,
/// render(), render_depth_only() and render_batch() are const and may be called concurrently
/// from several threads (each with its own output images). They run TBB-parallel over pixel tiles in the
/// caller's task arena; the result is identical for any number of threads.
class RgbdRenderer {
 public:
  /// Builds the mesh and the Embree scene (BVH build quality high, static scene). `world`
  /// should have passed validate(); it is not referenced after construction.
  /// Throws duet::Error(kInvalidArgument) for invalid settings or world geometry,
  /// kInternal when Embree fails.
  explicit RgbdRenderer(const World& world, const RenderSettings& settings = {});
  ~RgbdRenderer();
  RgbdRenderer(const RgbdRenderer&) = delete;
  RgbdRenderer& operator=(const RgbdRenderer&) = delete;
  RgbdRenderer(RgbdRenderer&&) noexcept;
  RgbdRenderer& operator=(RgbdRenderer&&) noexcept;

  /// Renders depth and colour of `sensor` (intrinsics, depth range and units) placed at
  /// T_world_optical (optical frame -> world). `out` is resized to the sensor's image size.
  /// Throws duet::Error(kInvalidArgument) for invalid intrinsics / depth range / units or a
  /// non-finite pose.
  void render(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical, std::uint64_t frame_seed,
              RgbdImage& out) const;

  /// As render() but without colour (out.rgb is left empty); the depth is identical.
  void render_depth_only(const SensorProfile& sensor, const Eigen::Isometry3f& T_world_optical,
                         std::uint64_t frame_seed, RgbdImage& out) const;

  /// Renders several frames (e.g. every sensor of the robot at one instant) in ONE parallel
  /// loop over the tiles of all of them: no barrier between the frames, so a few cores stay
  /// busy until the last tile. Every *jobs[i].out is identical to what render() (colour) or
  /// render_depth_only() (no colour) gives for that job alone, for any thread count. An empty
  /// span does nothing. Every job is validated before any output is touched: throws
  /// duet::Error(kInvalidArgument) for a null sensor or out, two jobs with the same out, or
  /// what render() throws.
  void render_batch(std::span<const RenderJob> jobs) const;

  [[nodiscard]] const RenderSettings& settings() const noexcept;
  [[nodiscard]] const WorldMesh& mesh() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace duet::sim
