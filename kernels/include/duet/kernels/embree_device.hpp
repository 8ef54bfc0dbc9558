#pragma once
/// @file embree_device.hpp
/// The one way duet creates an Embree device (the observation model's, the simulator's renderer).
///
/// Embree chooses its kernels by the CPU at run time (SSE, AVX2, AVX-512), and kernels of
/// different vector widths do not return bit-identical hits: a lockstep simulation that repeats
/// exactly on one machine then parts from the same run on a machine of another vector width
/// after a few hundred simulated seconds. duet caps Embree's ISA (kEmbreeDeviceConfig), so a run (a seed,
/// a profile, a map) gives the same bytes on every x86-64 CPU that has it; a CPU without it
/// runs Embree's narrower kernels, which may differ. The cap costs a one-thread render about
/// 16 % on an AVX-512 CPU and nothing measurable on two threads (bench/RESULTS.md, CI row 59).
#include <embree3/rtcore.h>

namespace duet {

/// The configuration every duet Embree device is created with: the widest ISA it may use.
inline constexpr const char* kEmbreeDeviceConfig = "max_isa=avx2";

/// A new Embree device with kEmbreeDeviceConfig. Throws duet::Error (kInternal), naming `who`
/// and Embree's error code, when Embree cannot create one. The caller releases it.
RTCDevice new_embree_device(const char* who);

}  // namespace duet
