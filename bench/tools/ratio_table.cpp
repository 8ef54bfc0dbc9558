// duet_ratio_table: reads the JSON of
//   duet_bench --benchmark_format=json --benchmark_repetitions=N
//              --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true
// (or --benchmark_out=FILE --benchmark_out_format=json) and prints a Markdown report: for each
// Kernel/size the median wall time of every impl, the ratio of the peer (pcl, else naive) to
// duet and to duet_1t, and the speed targets with PASS/MISS. It reports; it does not
// gate: the exit status is 0 whatever the ratios (2 only when the input cannot be read).
//
// Usage: duet_ratio_table BENCH.json [-o TABLE.md] [--note TEXT]...  (notes become bullets)
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

using nlohmann::json;

struct Run {
  std::vector<double> times_ns;                   // per-repetition real times (iteration entries)
  std::optional<double> median_ns, cv;            // from aggregates, when present
  std::optional<double> points, out, bytes;       // counters (median aggregate or last run)
  long family = 1L << 40;                         // registration order (family_index)
  std::string label, error;
};

struct Key {
  std::string kernel, impl, size;
};

double to_ns(double t, const std::string& unit) {
  if (unit == "us") return t * 1e3;
  if (unit == "ms") return t * 1e6;
  if (unit == "s") return t * 1e9;
  return t;  // ns
}

bool is_suffix_component(const std::string& c) {
  static const char* kPrefixes[] = {"real_time", "process_time", "manual_time", "threads:", "iterations:",
                                    "repeats:",  "min_time:",    "min_warmup_time:"};
  for (const char* p : kPrefixes)
    if (c.rfind(p, 0) == 0) return true;
  return false;
}

std::optional<Key> split_name(std::string name) {
  // Drop Google Benchmark's decorations (".../real_time", ".../threads:2", ...).
  for (;;) {
    const auto slash = name.rfind('/');
    if (slash == std::string::npos || !is_suffix_component(name.substr(slash + 1))) break;
    name.resize(slash);
  }
  const auto a = name.find('/');
  if (a == std::string::npos) return std::nullopt;
  const auto b = name.find('/', a + 1);
  if (b == std::string::npos) return Key{name.substr(0, a), name.substr(a + 1), "-"};
  return Key{name.substr(0, a), name.substr(a + 1, b - a - 1), name.substr(b + 1)};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string fmt_time(double ns) {
  char buf[64];
  if (ns < 1e3)
    std::snprintf(buf, sizeof buf, "%.0f ns", ns);
  else if (ns < 1e6)
    std::snprintf(buf, sizeof buf, "%.1f us", ns / 1e3);
  else if (ns < 1e9)
    std::snprintf(buf, sizeof buf, "%.2f ms", ns / 1e6);
  else
    std::snprintf(buf, sizeof buf, "%.3f s", ns / 1e9);
  return buf;
}

std::string fmt_ratio(double r) {
  char buf[32];
  std::snprintf(buf, sizeof buf, r >= 10 ? "%.1fx" : "%.2fx", r);
  return buf;
}

std::string fmt_count(double v) {
  char buf[32];
  if (v >= 1e6)
    std::snprintf(buf, sizeof buf, "%.2f M", v / 1e6);
  else if (v >= 1e4)
    std::snprintf(buf, sizeof buf, "%.1f k", v / 1e3);
  else
    std::snprintf(buf, sizeof buf, "%.0f", v);
  return buf;
}

enum class TargetKind {
  kRatio,      // time(kernel/peer/size) / time(kernel/impl/size) >= value
  kMaxTime,    // time(kernel/impl/size) <= value [ns]
  kBandwidth,  // (bytes/time of kernel/impl/size) / (bytes/time of `peer`, a full benchmark id) >= value
};

struct Target {
  std::string kernel, impl, peer;
  double value;
  std::string text;
  TargetKind kind = TargetKind::kRatio;
};

const std::vector<Target> kTargets{
    {"VoxelFilter", "duet_1t", "pcl", 4.0, "voxel filter: duet_1t >= 4x pcl::VoxelGrid"},
    {"VoxelFilter", "duet", "pcl", 7.0, "voxel filter: duet (2 threads) >= 7x pcl::VoxelGrid"},
    {"Normals", "duet", "pcl", 3.0, "normals: duet (2 threads) >= 3x pcl::NormalEstimationOMP (2 threads)"},
    {"Clustering", "duet", "pcl", 10.0, "clustering: duet (2 threads) >= 10x pcl::EuclideanClusterExtraction"},
    // Exploration kernels (issue 3).
    {"Observation", "duet_dda_1t", "naive", 4.0,
     "observation model (default DDA backend), 1 thread >= 4x the naive scalar DDA"},
    {"Decision", "duet", "", 10e6, "one decision (Procedure 1 N 100 I 5 phi_i = i + 1 H 4, 2 x 30 rays, + frontier search) <= 10 ms on 2 threads",
     TargetKind::kMaxTime},
    {"Decision", "duet", "duet_1t", 1.8, "one decision: speed-up 1 -> 2 threads >= 1.8x"},
    {"FrontierScan", "duet", "Memory/stream/128MiB", 0.5, "frontier full scan (2 threads) >= 0.5x the memory-streaming rate (2 threads)",
     TargetKind::kBandwidth},
    {"FrontierScan", "duet_1t", "Memory/stream_1t/128MiB", 0.5, "frontier full scan (1 thread) >= 0.5x the memory-streaming rate (1 thread)",
     TargetKind::kBandwidth},
    {"DWA", "duet_1t", "", 0.3e6, "dynamic window: 800 trajectories x 30 steps <= 0.3 ms on one core", TargetKind::kMaxTime},
    // Simulator (issue 4).
    {"Render", "duet", "", 15e6, "simulated RGB-D: both 640x480 frames (depth + colour + Kinect noise) <= 15 ms on 2 threads",
     TargetKind::kMaxTime},
};

}  // namespace

int main(int argc, char** argv) {
  std::string in_path, out_path;
  std::vector<std::string> notes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-o" && i + 1 < argc)
      out_path = argv[++i];
    else if (a == "--note" && i + 1 < argc)
      notes.emplace_back(argv[++i]);
    else if (a == "-h" || a == "--help") {
      std::cout << "usage: duet_ratio_table BENCH.json [-o TABLE.md] [--note TEXT]...\n";
      return 0;
    } else
      in_path = a;
  }
  if (in_path.empty()) {
    std::cerr << "usage: duet_ratio_table BENCH.json [-o TABLE.md] [--note TEXT]...\n";
    return 2;
  }
  json j;
  try {
    std::ifstream f(in_path);
    if (!f) throw std::runtime_error("cannot open " + in_path);
    j = json::parse(f);
  } catch (const std::exception& e) {
    std::cerr << "duet_ratio_table: " << e.what() << "\n";
    return 2;
  }

  // ---- collect
  std::map<std::string, Run> runs;         // by "kernel/impl/size"
  std::vector<std::string> kernel_order;   // first appearance
  std::map<std::string, std::vector<std::string>> size_order, impl_order;
  std::map<std::string, Key> keys;
  for (const auto& b : j.value("benchmarks", json::array())) {
    const std::string run_name = b.value("run_name", b.value("name", std::string()));
    const auto key = split_name(run_name);
    if (!key) continue;
    const std::string id = key->kernel + "/" + key->impl + "/" + key->size;
    if (!keys.count(id)) {
      keys[id] = *key;
      if (std::find(kernel_order.begin(), kernel_order.end(), key->kernel) == kernel_order.end())
        kernel_order.push_back(key->kernel);
      auto& so = size_order[key->kernel];
      if (std::find(so.begin(), so.end(), key->size) == so.end()) so.push_back(key->size);
      auto& io = impl_order[key->kernel];
      if (std::find(io.begin(), io.end(), key->impl) == io.end()) io.push_back(key->impl);
    }
    Run& r = runs[id];
    r.family = std::min(r.family, b.value("family_index", 1L << 40));
    if (b.value("error_occurred", false)) {
      r.error = b.value("error_message", std::string("error"));
      continue;
    }
    if (b.contains("label")) r.label = b["label"].get<std::string>();
    const std::string unit = b.value("time_unit", std::string("ns"));
    const std::string run_type = b.value("run_type", std::string("iteration"));
    auto counters = [&] {
      if (b.contains("points")) r.points = b["points"].get<double>();
      if (b.contains("out")) r.out = b["out"].get<double>();
      if (b.contains("bytes")) r.bytes = b["bytes"].get<double>();
    };
    if (run_type == "aggregate") {
      const std::string agg = b.value("aggregate_name", std::string());
      if (agg == "median") {
        r.median_ns = to_ns(b.value("real_time", 0.0), unit);
        counters();
      } else if (agg == "cv") {
        r.cv = b.value("real_time", 0.0);
      }
    } else {
      r.times_ns.push_back(to_ns(b.value("real_time", 0.0), unit));
      if (!r.median_ns) counters();
    }
  }
  // Report in registration order (random interleaving shuffles the JSON's order).
  auto first_family = [&](const std::string& kernel, const std::string* impl, const std::string* size) {
    long f = 1L << 40;
    for (const auto& [id, k] : keys)
      if (k.kernel == kernel && (!impl || k.impl == *impl) && (!size || k.size == *size)) f = std::min(f, runs[id].family);
    return f;
  };
  std::stable_sort(kernel_order.begin(), kernel_order.end(), [&](const std::string& a, const std::string& b) {
    return first_family(a, nullptr, nullptr) < first_family(b, nullptr, nullptr);
  });
  for (auto& [kernel, sizes] : size_order)
    std::stable_sort(sizes.begin(), sizes.end(), [&, k = kernel](const std::string& a, const std::string& b) {
      return first_family(k, nullptr, &a) < first_family(k, nullptr, &b);
    });
  for (auto& [kernel, impls] : impl_order)
    std::stable_sort(impls.begin(), impls.end(), [&, k = kernel](const std::string& a, const std::string& b) {
      return first_family(k, &a, nullptr) < first_family(k, &b, nullptr);
    });

  auto time_of = [&](const std::string& id) -> std::optional<double> {
    const auto it = runs.find(id);
    if (it == runs.end() || !it->second.error.empty()) return std::nullopt;
    if (it->second.median_ns) return it->second.median_ns;
    if (!it->second.times_ns.empty()) return median(it->second.times_ns);
    return std::nullopt;
  };
  auto cv_of = [&](const std::string& id) -> std::optional<double> {
    const auto it = runs.find(id);
    if (it == runs.end()) return std::nullopt;
    if (it->second.cv) return it->second.cv;
    const auto& t = it->second.times_ns;
    if (t.size() < 2) return std::nullopt;
    double m = 0;
    for (double x : t) m += x;
    m /= double(t.size());
    double v = 0;
    for (double x : t) v += (x - m) * (x - m);
    return std::sqrt(v / double(t.size() - 1)) / m;
  };

  // ---- report
  std::ostringstream md;
  const json ctx = j.value("context", json::object());
  md << "## duet_bench: median wall time per call, and speed-up of duet over the peer\n\n";
  if (!ctx.empty()) {
    md << "- run: " << ctx.value("date", std::string("?")) << " on `" << ctx.value("host_name", std::string("?"))
       << "`, " << ctx.value("num_cpus", 0) << " CPUs @ " << ctx.value("mhz_per_cpu", 0) << " MHz";
    if (ctx.contains("load_avg") && ctx["load_avg"].is_array() && !ctx["load_avg"].empty()) {
      md << ", load average at start";
      for (const auto& l : ctx["load_avg"]) {
        char buf[16];
        std::snprintf(buf, sizeof buf, " %.2f", l.get<double>());
        md << buf;
      }
    }
    md << "; benchmark library build: " << ctx.value("library_build_type", std::string("?")) << "\n";
    if (ctx.contains("duet_data")) md << "- data: " << ctx["duet_data"].get<std::string>() << "\n";
    if (ctx.contains("duet_input_dual")) md << "- input `dual`: " << ctx["duet_input_dual"].get<std::string>() << "\n";
    if (ctx.contains("duet_input_accum")) md << "- input `accum`: " << ctx["duet_input_accum"].get<std::string>() << "\n";
    if (ctx.contains("duet_pcl")) md << "- peers: " << ctx["duet_pcl"].get<std::string>() << "\n";
  }
  for (const auto& n : notes) md << "- " << n << "\n";
  bool any_synthetic = false;
  for (const auto& [id, r] : runs) any_synthetic = any_synthetic || r.label.find("SYNTHETIC") != std::string::npos;
  if (any_synthetic) md << "- **WARNING: inputs are a SYNTHETIC scene (../shared/data absent)**\n";
  md << "- duet = tbb::task_arena of 2 threads, duet_1t = arena of 1 thread; ratio = peer time / duet time "
        "(peer = pcl if present, else naive; > 1 means duet is faster); cv = largest coefficient of variation of "
        "the repetitions in the row\n\n";

  const std::vector<std::string> main_impls{"duet", "duet_1t", "pcl", "naive"};
  md << "| kernel | input | points | duet | duet_1t | pcl | naive | peer/duet | peer/duet_1t | out duet / peer | cv |\n";
  md << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  std::vector<std::string> reference_kernels;
  for (const auto& kernel : kernel_order) {
    const auto& impls = impl_order[kernel];
    const bool has_duet = std::count(impls.begin(), impls.end(), "duet") + std::count(impls.begin(), impls.end(), "duet_1t") > 0;
    if (!has_duet) {
      reference_kernels.push_back(kernel);
      continue;
    }
    for (const auto& size : size_order[kernel]) {
      auto id = [&](const std::string& impl) { return kernel + "/" + impl + "/" + size; };
      std::optional<double> points;
      for (const auto& impl : impls)
        if (runs.count(id(impl)) && runs[id(impl)].points) points = runs[id(impl)].points;
      md << "| " << kernel << " | " << size << " | " << (points ? fmt_count(*points) : "?") << " |";
      for (const auto& impl : main_impls) {
        const auto t = time_of(id(impl));
        if (t)
          md << " " << fmt_time(*t) << " |";
        else if (runs.count(id(impl)) && !runs[id(impl)].error.empty())
          md << " error |";
        else
          md << " - |";
      }
      const std::string peer = time_of(id("pcl")) ? "pcl" : (time_of(id("naive")) ? "naive" : "");
      for (const char* impl : {"duet", "duet_1t"}) {
        const auto td = time_of(id(impl));
        const auto tp = peer.empty() ? std::nullopt : time_of(id(peer));
        md << " " << (td && tp ? fmt_ratio(*tp / *td) : std::string("-")) << " |";
      }
      auto out_of = [&](const std::string& impl) -> std::string {
        const auto it = runs.find(id(impl));
        if (impl.empty() || it == runs.end() || !it->second.out.has_value()) return "-";
        return fmt_count(it->second.out.value());
      };
      md << " " << out_of("duet") << " / " << out_of(peer) << " |";
      double cv_max = -1;
      for (const auto& impl : impls)
        if (const auto c = cv_of(id(impl))) cv_max = std::max(cv_max, *c);
      if (cv_max >= 0) {
        char buf[16];
        std::snprintf(buf, sizeof buf, " %.1f%% |", cv_max * 100.0);
        md << buf;
      } else {
        md << " - |";
      }
      md << "\n";
    }
  }

  if (!reference_kernels.empty()) {
    md << "\nReference (no peer):\n\n| benchmark | median | bandwidth |\n|---|---:|---:|\n";
    for (const auto& kernel : reference_kernels)
      for (const auto& size : size_order[kernel])
        for (const auto& impl : impl_order[kernel]) {
          const std::string i = kernel + "/" + impl + "/" + size;
          const auto t = time_of(i);
          if (!t) continue;
          md << "| " << i << " | " << fmt_time(*t) << " | ";
          if (runs[i].bytes) {
            char buf[32];
            std::snprintf(buf, sizeof buf, "%.1f GB/s", *runs[i].bytes / *t);  // bytes per ns = GB/s
            md << buf;
          } else {
            md << "-";
          }
          md << " |\n";
        }
  }

  md << "\nTargets (from the issue; reported, not gated):\n\n| target | input | ratio | result |\n|---|---|---:|---|\n";
  int pass = 0, miss = 0, na = 0;
  for (const auto& t : kTargets) {
    const auto sizes = size_order.find(t.kernel);
    if (sizes == size_order.end()) {
      md << "| " << t.text << " | - | - | n/a (not run) |\n";
      ++na;
      continue;
    }
    for (const auto& size : sizes->second) {
      const std::string impl_id = t.kernel + "/" + t.impl + "/" + size;
      const std::string peer_id = t.kind == TargetKind::kBandwidth ? t.peer : t.kernel + "/" + t.peer + "/" + size;
      const auto td = time_of(impl_id);
      const auto tp = t.kind == TargetKind::kMaxTime ? std::optional<double>(1.0) : time_of(peer_id);
      md << "| " << t.text << " | " << size << " | ";
      if (!td || !tp) {
        md << "- | n/a (" << (!tp ? peer_id : impl_id) << " not run) |\n";
        ++na;
        continue;
      }
      bool ok = false;
      if (t.kind == TargetKind::kMaxTime) {
        ok = *td <= t.value;
        md << fmt_time(*td) << " | " << (ok ? "PASS" : "MISS") << " (<= " << fmt_time(t.value) << ") |\n";
      } else if (t.kind == TargetKind::kBandwidth) {
        const auto bi = runs[impl_id].bytes, bp = runs[peer_id].bytes;
        if (!bi || !bp) {
          md << "- | n/a (no byte counts) |\n";
          ++na;
          continue;
        }
        const double r = (*bi / *td) / (*bp / *tp);
        ok = r >= t.value;
        md << fmt_ratio(r) << " | " << (ok ? "PASS" : "MISS") << " (>= " << fmt_ratio(t.value) << ") |\n";
      } else {
        const double r = *tp / *td;
        ok = r >= t.value;
        md << fmt_ratio(r) << " | " << (ok ? "PASS" : "MISS") << " (>= " << fmt_ratio(t.value) << ") |\n";
      }
      (ok ? pass : miss)++;
    }
  }
  md << "\n" << pass << " PASS, " << miss << " MISS, " << na << " n/a\n";

  for (const auto& [id, r] : runs)
    if (!r.error.empty()) md << "\n- " << id << ": ERROR " << r.error;

  std::cout << md.str();
  if (!out_path.empty()) {
    std::ofstream o(out_path);
    o << md.str();
    if (!o) {
      std::cerr << "duet_ratio_table: cannot write " << out_path << "\n";
      return 2;
    }
  }
  return 0;
}
