#pragma once
/// @file embree_device.hpp
/// The one way duet creates an Embree device (the observation model's, the simulator's renderer).
///
/// Embree chooses its kernels by the CPU at run time (SSE, AVX2, AVX-512). Their hit distances go
/// through an approximate reciprocal (rcpps with a Newton step; rcp14 on AVX-512), so the kernel
/// families differ in the last bits and, rarely, in which of two surfaces a ray meets first. rcp14
/// gives the same bits on Intel and AMD CPUs; rcpps does not. Measured on the lab's frames
/// (tests: SimRendererIsa.*) and on whole runs: Embree's AVX-512 kernels give the same bytes on an
/// Intel Xeon and an AMD Zen 5; its AVX2 kernels give the same bytes on AMD Zen 3 and Zen 5 but
/// others on the Intel Xeon. So duet lets Embree use the widest kernels the CPU has: a lockstep
/// run (a seed, a profile, a map) repeats on every CPU with AVX-512, and on CPUs of one vendor
/// without it. To repeat a run made on another machine, set DUET_EMBREE_CONFIG to its kernels
/// (e.g. "max_isa=avx2" on an AVX-512 CPU of the same vendor).
///
/// The observation model takes only the cell face from Embree and computes the distance itself
/// (observation_embree.cpp): its distances do not depend on the kernels (test:
/// ObservationModel.EmbreeGivesTheSameBytesWithEveryKernel). The renderer keeps
/// Embree's distances: recomputing them and choosing the nearest surface in an intersection
/// filter made the frames the same with every kernel but cost 50 % of the render (AVX2 kernels, bench
/// Render/duet/dual_640x480 10.1 -> 15.1 ms), and Embree's AVX2 coherent packet traversal still
/// lets rays through a wall at places (bench/RESULTS.md, stop 60).
#include <embree3/rtcore.h>

#include <string>

namespace duet {

/// The configuration duet's Embree devices are created with unless DUET_EMBREE_CONFIG is set:
/// none, so Embree uses the widest kernels the CPU has.
inline constexpr const char* kEmbreeDeviceConfig = "";

/// The configuration new_embree_device() uses: the environment's DUET_EMBREE_CONFIG when set
/// (Embree's syntax, e.g. "max_isa=avx2" or "max_isa=sse4.2,verbose=1"), else kEmbreeDeviceConfig.
std::string embree_device_config();

/// A new Embree device with embree_device_config(). Throws duet::Error (kInternal), naming `who`,
/// the configuration and where it came from, and Embree's error code, when Embree cannot create
/// one (for instance DUET_EMBREE_CONFIG=threads=abc). Embree itself ignores keys and ISA names
/// it does not know (max_isa=bogus: its widest kernels). The caller releases it.
RTCDevice new_embree_device(const char* who);

}  // namespace duet
