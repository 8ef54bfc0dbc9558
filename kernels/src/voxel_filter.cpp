#include <duet/kernels/error.hpp>
#include <duet/kernels/voxel_filter.hpp>

#include "parallel.hpp"
#include "radix_sort.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace duet {

void validate(const VoxelFilterSettings& s) {
  if (!(s.leaf_size_m > 0.0f) || !std::isfinite(s.leaf_size_m))
    fail(ErrorCode::kInvalidArgument, "VoxelFilterSettings.leaf_size_m must be finite and > 0 m, got " +
                                          std::to_string(s.leaf_size_m));
  if (s.min_points_per_voxel < 1)
    fail(ErrorCode::kInvalidArgument, "VoxelFilterSettings.min_points_per_voxel must be >= 1");
}

namespace {

constexpr std::size_t kBlock = 1 << 15;
constexpr std::int32_t kBadIndex = std::numeric_limits<std::int32_t>::min();  // cvttss2si's "invalid"

// floor(s) as int32 as the x86 conversion does it: kBadIndex when s is NaN, infinite or
// outside [-2^31, 2^31) - the same rule as the vector path below.
inline std::int32_t floor_index(float s) {
  if (!(s >= -2147483648.0f && s < 2147483648.0f)) return kBadIndex;
  const auto i = static_cast<std::int32_t>(s);
  return i - (s < static_cast<float>(i) ? 1 : 0);
}

// --- per-thread tables: integer cell -> sums, in the slot ------------------------------------
using Table = detail::VoxelCellTable;
using Sums = detail::VoxelCellSums;
using Block = detail::VoxelBlock;

inline std::uint64_t cell_hash(std::int32_t x, std::int32_t y, std::int32_t z, int shift) {
  const std::uint64_t h = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) |
                           static_cast<std::uint64_t>(static_cast<std::uint32_t>(y)) << 32) *
                              0x9E3779B97F4A7C15ull ^
                          static_cast<std::uint64_t>(static_cast<std::uint32_t>(z)) * 0xC2B2AE3D27D4EB4Full;
  return h >> shift;
}

void table_resize(Table& t, std::size_t cap) {
  t.slots.assign(cap, Table::Slot{});
  t.mask = cap - 1;
  t.shift = 64 - std::countr_zero(cap);
}

[[gnu::noinline]] void table_grow(Table& t) {
  std::vector<Table::Slot> old(2 * t.slots.size());
  old.swap(t.slots);
  t.mask = t.slots.size() - 1;
  t.shift = 64 - std::countr_zero(t.slots.size());
  for (std::uint32_t& u : t.used) {
    const Sums& s = old[u].s;
    std::uint64_t h = cell_hash(s.x, s.y, s.z, t.shift);
    while (t.slots[h].s.count != 0) h = (h + 1) & t.mask;
    t.slots[h].s = s;
    u = static_cast<std::uint32_t>(h);
  }
}

// Adds the sums of one run of consecutive points in one voxel (Sums or VoxelRunRecord: cell
// x, y, z and sums sx, sy, sz, r, g, b, count) to the block's hash table (open addressing,
// linear probing, load <= 1/2); h = cell_hash() of its cell. Callers prefetch slot h early:
// runs average ~4 points on Kinect frames, so the table's L2 latency would otherwise be paid
// every few points.
template <class RunSums>
inline void table_add(Table& t, const RunSums& run, std::uint64_t h) {
  while (true) {
    Sums& s = t.slots[h].s;
    if (s.count == 0) {
      if (2 * (t.used.size() + 1) > t.slots.size()) [[unlikely]] {
        table_grow(t);
        table_add(t, run, cell_hash(run.x, run.y, run.z, t.shift));
        return;
      }
      s.x = run.x;
      s.y = run.y;
      s.z = run.z;
      t.used.push_back(static_cast<std::uint32_t>(h));
      break;
    }
    if (s.x == run.x && s.y == run.y && s.z == run.z) break;
    h = (h + 1) & t.mask;
  }
  Sums& s = t.slots[h].s;
  s.sx += run.sx;
  s.sy += run.sy;
  s.sz += run.sz;
  s.r += run.r;
  s.g += run.g;
  s.b += run.b;
  s.count += run.count;
}

// A point whose cell has a kBadIndex coordinate: skipped if not finite (as PCL), otherwise its
// voxel index does not fit: the first such coordinate of the block is kept for the error.
inline void reject(Block& m, const float* p, const std::int32_t* idx) {
  if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) return;
  for (int a = 0; a < 3; ++a) {
    if (idx[a] == kBadIndex && !m.out_of_range) {
      m.out_of_range = true;
      m.bad_value = p[a];
      m.bad_axis = a;
    }
  }
}

#if defined(__SSE2__)
using RunRecord = detail::VoxelRunRecord;
static_assert(sizeof(RunRecord) == 64);

// The hot loop, in two phases per chunk of points, with no data-dependent branch in phase 1:
//  1. one point per iteration in one SSE register (x, y, z, 0): floor of the three coordinates
//     in four instructions; "same voxel as the previous point" as an all-lanes mask that both
//     resets the running sums at a run start (sums = (sums & same) + point) and advances the
//     run counter (k += 1 + same), so runs are written out without a branch. Kinect runs
//     average ~4 points, where a branch per run would mispredict every few points.
//  2. the chunk's runs go into the block's hash table, the slot of a later run prefetched.
// Reads 16 bytes per point: the caller keeps [begin, end) where that stays inside the view.
template <bool kColor>
std::size_t vector_points(PointsView points, ColorsView colors, float inv, std::size_t begin, std::size_t end,
                          Table& table, Block& m, std::vector<RunRecord>& runs) {
  constexpr std::size_t kChunk = 2048;
  const __m128 vinv = _mm_set1_ps(inv);
  const __m128 xyz_mask = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
  const __m128i bad = _mm_set1_epi32(kBadIndex);
  const __m128i one_count = _mm_setr_epi32(0, 0, 0, 1);
  const std::byte* base = reinterpret_cast<const std::byte*>(points.ptr(0));
  const std::size_t stride = points.stride_bytes();
  if (runs.size() < kChunk + 1) runs.resize(kChunk + 1);
  for (std::size_t c0 = begin; c0 < end; c0 += kChunk) {
    const std::size_t c1 = std::min(end, c0 + kChunk);
    // Phase 1. runs[k] holds the current run; a chunk starts a new run (k = 0 at its first point).
    RunRecord* rec = runs.data();
    std::size_t k = std::numeric_limits<std::size_t>::max();  // k + 1 == 0 at the first run
    __m128i prev = bad;  // no valid cell equals it: the first point starts a run
    __m128d sxy = _mm_setzero_pd(), sz = _mm_setzero_pd();
    __m128i ci = _mm_setzero_si128();  // r, g, b, count
    for (std::size_t i = c0; i < c1; ++i) {
      const float* p = reinterpret_cast<const float*>(base + i * stride);
      const __m128 v = _mm_and_ps(_mm_loadu_ps(p), xyz_mask);
      const __m128 s = _mm_mul_ps(v, vinv);
      __m128i t = _mm_cvttps_epi32(s);
      if (_mm_movemask_epi8(_mm_cmpeq_epi32(t, bad)) & 0x0FFF) [[unlikely]] {
        alignas(16) std::int32_t idx[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(idx), t);
        for (int a = 0; a < 3; ++a) idx[a] = idx[a] == kBadIndex ? kBadIndex : floor_index(s[a]);
        reject(m, p, idx);
        continue;
      }
      // floor: truncation rounds negative non-integers up; subtract 1 there (mask = -1).
      t = _mm_add_epi32(t, _mm_castps_si128(_mm_cmplt_ps(s, _mm_cvtepi32_ps(t))));
      __m128i same = _mm_cmpeq_epi32(t, prev);
      same = _mm_and_si128(same, _mm_shuffle_epi32(same, _MM_SHUFFLE(2, 3, 0, 1)));
      same = _mm_and_si128(same, _mm_shuffle_epi32(same, _MM_SHUFFLE(1, 0, 3, 2)));  // all lanes: all equal
      k += static_cast<std::size_t>(1 + _mm_cvtsi128_si32(same));                       // +1 at a run start
      prev = t;
      const __m128d same_pd = _mm_castsi128_pd(same);
      sxy = _mm_add_pd(_mm_and_pd(sxy, same_pd), _mm_cvtps_pd(v));
      sz = _mm_add_pd(_mm_and_pd(sz, same_pd), _mm_cvtps_pd(_mm_movehl_ps(v, v)));
      __m128i add = one_count;
      if constexpr (kColor) {
        const std::uint8_t* c = colors.ptr(i);
        const int rgb = c[0] | c[1] << 8 | c[2] << 16 | 1 << 24;
        const __m128i zero = _mm_setzero_si128();
        add = _mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128(rgb), zero), zero);
      }
      ci = _mm_add_epi32(_mm_and_si128(ci, same), add);
      auto* out = reinterpret_cast<__m128i*>(rec + k);
      _mm_store_si128(out, t);
      _mm_store_pd(reinterpret_cast<double*>(out + 1), sxy);
      _mm_store_pd(reinterpret_cast<double*>(out + 2), sz);
      _mm_store_si128(out + 3, ci);
    }
    // Phase 2: the runs into the table (independent lookups; prefetch a few runs ahead).
    const std::size_t nruns = k + 1;  // 0 when every point of the chunk was rejected
    constexpr std::size_t kAhead = 8;
    for (std::size_t r = 0; r < std::min(kAhead, nruns); ++r)
      __builtin_prefetch(&table.slots[cell_hash(rec[r].x, rec[r].y, rec[r].z, table.shift)], 1);
    for (std::size_t r = 0; r < nruns; ++r) {
      if (r + kAhead < nruns) {
        const RunRecord& f = rec[r + kAhead];
        __builtin_prefetch(&table.slots[cell_hash(f.x, f.y, f.z, table.shift)], 1);
      }
      const RunRecord& q = rec[r];
      table_add(table, q, cell_hash(q.x, q.y, q.z, table.shift));
    }
  }
  return end;
}
#endif

// Accumulates points [begin, end) into the block map m. Voxel of p: floor(p * inv) per axis in
// float, exactly as pcl::VoxelGrid (its floor(p[a] * inverse_leaf_size_[a])).
void accumulate_block(PointsView points, ColorsView colors, float inv, std::size_t begin, std::size_t end,
                      Table& table, Block& m) {
  const bool with_color = !colors.empty();
  // The scalar path (points the vector path cannot load, or no SSE2): runs summed in `run`
  // (count 0 = no open run).
  Sums run;
  auto flush = [&] {
    if (run.count == 0) return;
    table_add(table, run, cell_hash(run.x, run.y, run.z, table.shift));
    run = Sums{};
  };
  auto scalar_point = [&](std::size_t i) {
    const float* p = points.ptr(i);
    const std::int32_t idx[3] = {floor_index(p[0] * inv), floor_index(p[1] * inv), floor_index(p[2] * inv)};
    if (idx[0] == kBadIndex || idx[1] == kBadIndex || idx[2] == kBadIndex) {
      reject(m, p, idx);
      return;
    }
    if (run.count == 0 || run.x != idx[0] || run.y != idx[1] || run.z != idx[2]) {
      flush();
      run.x = idx[0];
      run.y = idx[1];
      run.z = idx[2];
    }
    run.sx += static_cast<double>(p[0]);
    run.sy += static_cast<double>(p[1]);
    run.sz += static_cast<double>(p[2]);
    ++run.count;
    if (with_color) {
      const std::uint8_t* c = colors.ptr(i);
      run.r += c[0];
      run.g += c[1];
      run.b += c[2];
    }
  };
  std::size_t i = begin;
#if defined(__SSE2__)
  // A 16-byte load reads 4 bytes past the point, so the last point(s) of the view (when the
  // stride is < 16 bytes) take the scalar path.
  const std::size_t stride = points.stride_bytes();
  // Points whose 16-byte load stays inside the view: i * stride + 16 <= (n - 1) * stride + 12.
  const std::size_t n = points.size();
  const std::size_t tail = stride >= 16 ? 0 : stride == 0 ? n : (4 + stride - 1) / stride;
  const std::size_t vec_end = std::min(end, n > tail ? n - tail : 0);
  if (i < vec_end) {
    i = with_color ? vector_points<true>(points, colors, inv, i, vec_end, table, m, table.runs)
                   : vector_points<false>(points, colors, inv, i, vec_end, table, m, table.runs);
  }
#endif
  for (; i < end; ++i) scalar_point(i);
  flush();
  // Hand the block's cells over in first-seen order and leave the table empty for the next block.
  m.cells.resize(table.used.size());
  std::int32_t lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, hi[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  for (std::size_t k = 0; k < table.used.size(); ++k) {
    Sums& s = table.slots[table.used[k]].s;
    m.cells[k] = s;
    lo[0] = std::min(lo[0], s.x), hi[0] = std::max(hi[0], s.x);
    lo[1] = std::min(lo[1], s.y), hi[1] = std::max(hi[1], s.y);
    lo[2] = std::min(lo[2], s.z), hi[2] = std::max(hi[2], s.z);
    s = Sums{};
  }
  table.used.clear();
  for (int a = 0; a < 3; ++a) m.lo[a] = lo[a], m.hi[a] = hi[a];
}

}  // namespace

void voxel_filter(PointsView points, ColorsView colors, const VoxelFilterSettings& settings,
                  VoxelFilterWorkspace& ws, PointCloud& out) {
  validate(settings);
  const std::size_t n = points.size();
  const bool with_color = !colors.empty();
  if (with_color && colors.size() != n)
    fail(ErrorCode::kInvalidArgument, "voxel_filter: " + std::to_string(colors.size()) + " colours for " +
                                          std::to_string(n) + " points");
  if (n >= std::numeric_limits<std::uint32_t>::max())
    fail(ErrorCode::kInvalidArgument, "voxel_filter: more than 2^32-2 points");
  // In-place use (out is the cloud being viewed): filter into a temporary, then move.
  auto overlaps = [](const void* p, const void* b, std::size_t bytes) {
    const auto pi = reinterpret_cast<std::uintptr_t>(p), bi = reinterpret_cast<std::uintptr_t>(b);
    return p != nullptr && b != nullptr && pi >= bi && pi < bi + bytes;
  };
  if (n > 0 && (overlaps(points.ptr(0), out.points.data(), out.points.size() * sizeof(Eigen::Vector3f)) ||
                (with_color && overlaps(colors.ptr(0), out.colors.data(), out.colors.size() * sizeof(Rgb8))))) {
    PointCloud tmp;
    voxel_filter(points, colors, settings, ws, tmp);
    out = std::move(tmp);
    return;
  }
  out.clear();
  if (n == 0) return;
  const float inv = 1.0f / settings.leaf_size_m;

  // 1. Per fixed block: sums per integer voxel cell, in one pass over the points (no separate
  //    bounds pass: the cells' range is found from the distinct cells afterwards).
  const std::size_t nb = detail::block_count(n, kBlock);
  if (ws.blocks.size() < nb) ws.blocks.resize(nb);
  // One table per thread index. current_thread_index() can equal max_concurrency(): oneTBB
  // gives an arena with a reserved slot at least two slots, the second for a worker that runs
  // work enqueued into it, so a call into a busy one-thread arena runs at index 1.
  const auto threads = static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()) + 1;
  if (ws.tables.size() < threads) ws.tables.resize(threads);
  for (Table& t : ws.tables)
    if (t.slots.empty()) table_resize(t, 1024);
  detail::for_blocks(n, kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    Block& m = ws.blocks[b];
    m.out_of_range = false;
    const auto thread = static_cast<std::size_t>(tbb::this_task_arena::current_thread_index());
    if (thread >= ws.tables.size()) [[unlikely]]
      fail(ErrorCode::kInternal, "voxel_filter: thread index " + std::to_string(thread) + " beyond the " +
                                     std::to_string(ws.tables.size()) + " per-thread tables");
    accumulate_block(points, colors, inv, begin, end, ws.tables[thread], m);
  });

  // 2. Range: any finite coordinate with |p / leaf| >= 2^31 is an error (the first one in input
  //    order is reported), as is a bounding box of more than 2^63 voxels. Never a wrong result.
  std::int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  ws.offsets.resize(nb + 1);
  std::size_t ncells = 0;
  for (std::size_t b = 0; b < nb; ++b) {
    const Block& m = ws.blocks[b];
    if (m.out_of_range)
      fail(ErrorCode::kOutOfRange, "voxel_filter: coordinate " + std::to_string(m.bad_value) + " m on axis " +
                                       "xyz"[m.bad_axis] + " is too large for a voxel index at leaf " +
                                       std::to_string(settings.leaf_size_m) + " m (|p / leaf| must be < 2^31)");
    ws.offsets[b] = ncells;
    ncells += m.cells.size();
    if (m.cells.empty()) continue;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min<std::int64_t>(lo[a], m.lo[a]);
      hi[a] = std::max<std::int64_t>(hi[a], m.hi[a]);
    }
  }
  ws.offsets[nb] = ncells;
  if (ncells == 0) return;  // no finite point
  std::uint64_t total = 0, dxy = 0;
  const auto div = [&](int a) { return static_cast<std::uint64_t>(hi[a] - lo[a] + 1); };
  const bool overflow = __builtin_mul_overflow(div(0), div(1), &dxy) ||
                        __builtin_mul_overflow(dxy, div(2), &total) || total >= (std::uint64_t{1} << 63);
  if (overflow)
    fail(ErrorCode::kOutOfRange, "voxel_filter: the bounding box holds more than 2^63 voxels at leaf " +
                                     std::to_string(settings.leaf_size_m) + " m; the voxel index would overflow");

  // 3. Linear voxel index of every block cell, z-major (PCL's order):
  //    (x - min_x) + (y - min_y) * div_x + (z - min_z) * div_x * div_y; then a stable sort by index,
  //    so the cells of one voxel end up together in block order (deterministic sums).
  const std::uint64_t mul_y = div(0), mul_z = dxy;
  ws.keys.resize(ncells);
  ws.order.resize(ncells);
  detail::for_blocks(nb, 1, [&](std::size_t b, std::size_t, std::size_t) {
    const auto& cells = ws.blocks[b].cells;
    const std::size_t off = ws.offsets[b];
    for (std::size_t k = 0; k < cells.size(); ++k) {
      const Sums& c = cells[k];
      ws.keys[off + k] = static_cast<std::uint64_t>(c.x - lo[0]) + static_cast<std::uint64_t>(c.y - lo[1]) * mul_y +
                         static_cast<std::uint64_t>(c.z - lo[2]) * mul_z;
      ws.order[off + k] = static_cast<std::uint32_t>(off + k);
    }
  });
  detail::radix_sort_pairs(ws.keys, ws.order, ws.keys_tmp, ws.order_tmp, total - 1);

  // 4. Voxels = runs of equal keys. Fixed chunks of the sorted cells (a voxel belongs to the
  //    chunk where its run starts); pass A counts the kept voxels per chunk, pass B writes the
  //    centroids and mean colours at their prefix offsets. Voxels below min_points_per_voxel
  //    are dropped.
  ws.cell_ptr.resize(ncells);
  detail::for_blocks(nb, 1, [&](std::size_t b, std::size_t, std::size_t) {
    const auto& cells = ws.blocks[b].cells;
    const std::size_t off = ws.offsets[b];
    for (std::size_t k = 0; k < cells.size(); ++k) ws.cell_ptr[off + k] = &cells[k];
  });
  constexpr std::size_t kChunk = 4096;
  const std::size_t nchunks = detail::block_count(ncells, kChunk);
  const std::uint32_t min_pts = settings.min_points_per_voxel;
  ws.chunk_kept.assign(nchunks + 1, 0);
  const auto* keys = ws.keys.data();
  const auto* order = ws.order.data();
  const auto* ptrs = ws.cell_ptr.data();
  // Calls fn(first, last) for each voxel whose run of sorted cells starts in [begin, end).
  auto for_voxels = [&](std::size_t begin, std::size_t end, auto&& fn) {
    std::size_t j = begin;
    while (j < end && j > 0 && keys[j] == keys[j - 1]) ++j;  // run started in the previous chunk
    while (j < end) {
      std::size_t e = j + 1;
      while (e < ncells && keys[e] == keys[j]) ++e;
      fn(j, e);
      j = e;
    }
  };
  auto count_of = [&](std::size_t first, std::size_t last) {
    std::uint64_t c = 0;
    for (std::size_t j = first; j < last; ++j) c += ptrs[order[j]]->count;
    return c;
  };
  detail::for_blocks(ncells, kChunk, [&](std::size_t c, std::size_t begin, std::size_t end) {
    std::size_t kept = 0;
    if (min_pts <= 1) {  // every voxel is kept: count the runs from the keys alone
      for (std::size_t j = begin; j < end; ++j) kept += (j == 0 || keys[j] != keys[j - 1]) ? 1u : 0u;
    } else {
      for_voxels(begin, end, [&](std::size_t first, std::size_t last) { kept += count_of(first, last) >= min_pts ? 1u : 0u; });
    }
    ws.chunk_kept[c + 1] = kept;
  });
  for (std::size_t c = 0; c < nchunks; ++c) ws.chunk_kept[c + 1] += ws.chunk_kept[c];
  const std::size_t kept = ws.chunk_kept[nchunks];
  out.points.resize(kept);
  if (with_color) out.colors.resize(kept);
  detail::for_blocks(ncells, kChunk, [&](std::size_t c, std::size_t begin, std::size_t end) {
    std::size_t v = ws.chunk_kept[c];
    for_voxels(begin, end, [&](std::size_t first, std::size_t last) {
      double x = 0, y = 0, z = 0;
      std::uint64_t r = 0, g = 0, b = 0, cnt = 0;
      for (std::size_t j = first; j < last; ++j) {
        if (j + 16 < ncells) __builtin_prefetch(ptrs[order[j + 16]]);  // the cells are scattered
        const Sums& s = *ptrs[order[j]];
        x += s.sx;
        y += s.sy;
        z += s.sz;
        r += s.r;
        g += s.g;
        b += s.b;
        cnt += s.count;
      }
      if (cnt < min_pts) return;
      const double dn = static_cast<double>(cnt);
      out.points[v] = Eigen::Vector3f(static_cast<float>(x / dn), static_cast<float>(y / dn), static_cast<float>(z / dn));
      if (with_color) {
        const std::uint64_t h = cnt / 2;
        out.colors[v] = Rgb8{static_cast<std::uint8_t>((r + h) / cnt), static_cast<std::uint8_t>((g + h) / cnt),
                             static_cast<std::uint8_t>((b + h) / cnt)};
      }
      ++v;
    });
  });
}

void voxel_filter(PointsView points, ColorsView colors, const VoxelFilterSettings& settings, PointCloud& out) {
  VoxelFilterWorkspace ws;
  voxel_filter(points, colors, settings, ws, out);
}

}  // namespace duet
