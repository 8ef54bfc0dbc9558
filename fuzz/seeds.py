#!/usr/bin/env python3
"""Writes the checked-in seed inputs of the fuzz targets (fuzz/corpus/<target>/seed-*): small,
valid files of every format and layout the readers accept, made here so the corpus needs no
data from outside the repository. scripts/fuzz.sh adds the real files of ../shared/data and
the project's profiles and worlds as further seeds. Regression inputs (crash-*, hang-*) found
by fuzzing sit beside the seeds and are never rewritten by this script.

Usage: python3 fuzz/seeds.py"""
import math
import os
import random
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SEP = b"\n--duet-fuzz-part--\n"


def put(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


def lzf_literal(raw):
    """An LZF stream of literal runs only (valid LZF: control byte n-1, then n bytes)."""
    out = bytearray()
    for i in range(0, len(raw), 32):
        chunk = raw[i:i + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)


def pcd_seeds():
    pts = [(0.1 * i, -0.05 * i, 1.0 + 0.01 * i) for i in range(6)]
    rgb = [struct.unpack("<f", struct.pack("<I", (200 << 16) | (100 << 8) | (10 * i)))[0] for i in range(6)]
    head = ("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\n"
            "TYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 6\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\n")
    ascii = head + "DATA ascii\n" + "".join("%g %g %g %.9g\n" % (p + (c,)) for p, c in zip(pts, rgb))
    put("pcd", "ascii.pcd", ascii.encode())
    binary = b"".join(struct.pack("<4f", *(p + (c,))) for p, c in zip(pts, rgb))
    put("pcd", "binary.pcd", (head + "DATA binary\n").encode() + binary)
    # binary_compressed: fields one after another (SoA), then LZF.
    soa = b"".join(struct.pack("<f", p[k]) for k in range(3) for p in pts) + b"".join(struct.pack("<f", c) for c in rgb)
    comp = lzf_literal(soa)
    put("pcd", "compressed.pcd", (head + "DATA binary_compressed\n").encode() + struct.pack("<II", len(comp), len(soa)) + comp)
    organized = head.replace("WIDTH 6\nHEIGHT 1", "WIDTH 3\nHEIGHT 2").replace("FIELDS x y z rgb", "FIELDS x y z rgba")
    put("pcd", "organized.pcd", (organized + "DATA binary\n").encode() + binary)
    xyz = ("VERSION .7\nFIELDS x y z normal_x normal_y normal_z curvature\nSIZE 4 4 4 4 4 4 4\nTYPE F F F F F F F\n"
           "COUNT 1 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3 0 0 1 0.1\nnan nan nan nan nan nan nan\n")
    put("pcd", "normals.pcd", xyz.encode())


def ply_seeds():
    pts = [(0.1 * i, 0.2, 1.0 - 0.1 * i, 10 * i, 20, 30) for i in range(5)]
    head = ("ply\nformat %s 1.0\ncomment duet seed\nelement vertex 5\nproperty float x\nproperty float y\n"
            "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n")
    put("ply", "ascii.ply", (head % "ascii" + "".join("%g %g %g %d %d %d\n" % p for p in pts) + "3 0 1 2\n").encode())
    le = b"".join(struct.pack("<3f3B", *p) for p in pts) + struct.pack("<B3i", 3, 0, 1, 2)
    put("ply", "binary_le.ply", (head % "binary_little_endian").encode() + le)
    be = b"".join(struct.pack(">3f3B", *p) for p in pts) + struct.pack(">B3i", 3, 0, 1, 2)
    put("ply", "binary_be.ply", (head % "binary_big_endian").encode() + be)
    dbl = ("ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
           "property double z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n").encode()
    dbl += struct.pack("<3d3f", 1, 2, 3, 0, 0, 1) + struct.pack("<3d3f", 4, 5, 6, 1, 0, 0)
    put("ply", "double.ply", dbl)


def pgm(w, h, cells, maxval=255):
    if maxval > 255:
        return b"P5\n%d %d\n%d\n" % (w, h, maxval) + b"".join(struct.pack(">H", c) for c in cells)
    return b"P5\n# duet seed\n%d %d\n%d\n" % (w, h, maxval) + bytes(cells)


def room(w, h):
    cells = []
    for y in range(h):
        for x in range(w):
            wall = x in (0, w - 1) or y in (0, h - 1) or (x == w // 2 and y != h // 2)
            cells.append(0 if wall else 254)
    return cells


def map_seeds():
    yaml = b"image: map.pgm\nresolution: 0.1\norigin: [-1.0, -0.5, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    put("map_server", "trinary", yaml + SEP + pgm(24, 16, room(24, 16)))
    put("map_server", "scale16", yaml.replace(b"free_thresh: 0.196\n", b"free_thresh: 0.196\nmode: scale\n") + SEP +
        pgm(24, 16, [c * 257 for c in room(24, 16)], 65535))
    ascii = b"P2\n6 4\n255\n" + b" ".join(b"%d" % c for c in room(6, 4)) + b"\n"
    put("map_server", "p2", yaml.replace(b"negate: 0", b"negate: 1") + SEP + ascii)


def world_seeds():
    world = b"""name: seed room
floor: {min: [0.0, 0.0], max: [6.0, 4.0]}
start: [1.0, 1.0, 0.0]
target_region: {min: [4.5, 2.5], max: [5.8, 3.8]}
walls:
  - {name: outer, points: [[0.05, 0.05], [5.95, 0.05], [5.95, 3.95], [0.05, 3.95]], closed: true, thickness_m: 0.1}
boxes:
  - {name: box, centre: [3.0, 2.0], size: [0.5, 0.8], yaw_deg: 30, height_m: 0.7}
polygons:
  - {name: wedge, points: [[4.0, 0.5], [5.0, 0.5], [4.5, 1.2]], z_m: [0.0, 1.0]}
"""
    put("world", "yaml", world)
    map_world = b"image: map.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\n"
    put("world", "map", map_world + SEP + pgm(30, 20, room(30, 20)))


def png(w, h, channels, bits, rows):
    color_type = {1: 0, 3: 2, 4: 6}[channels]
    raw = b"".join(b"\x00" + r for r in rows)
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, bits, color_type, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def rgbd_seeds():
    w, h = 8, 6  # slambook2 seeds set the harness's 8x6 intrinsics (first byte bit 1)

    colour = png(w, h, 3, 8, [b"".join(bytes([x & 255, y & 255, 90]) for x in range(w)) for y in range(h)])
    depth_rows = [b"".join(struct.pack(">H", 1000 + 2 * x + y if (x + y) % 5 else 0) for x in range(w)) for y in range(h)]
    depth_png = png(w, h, 1, 16, depth_rows)
    depth_pgm = b"P5\n%d %d\n65535\n" % (w, h) + b"".join(depth_rows)
    poses = b"0 0 0 0 0 0 1\n0.1 0 0.02 0 0.0499792 0 0.99875\n"
    put("rgbd", "slambook2", b"\x02" + SEP.join([poses, colour, depth_pgm, colour, depth_png]))
    intr = b"5.0 0 3.5\n0 5.0 2.5\n0 0 1\n"
    pose0 = b"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
    pose1 = b"1 0 0 0.1\n0 1 0 0\n0 0 1 0.05\n0 0 0 1\n"
    put("rgbd", "3dmatch", b"\x01" + SEP.join([intr, colour, depth_png, pose0, colour, depth_png, pose1]))
    rgb_txt = b"# timestamp filename\n1.000 1.png\n1.033 2.png\n"
    depth_txt = b"# timestamp filename\n1.001 1_depth.png\n1.034 2_depth.png\n"
    gt = b"# timestamp tx ty tz qx qy qz qw\n0.999 0 0 0 0 0 0 1\n1.035 0.01 0 0 0 0 0 1\n"
    put("rgbd", "tum", b"\x06" + SEP.join([rgb_txt, depth_txt, gt, intr, colour, depth_png, colour, depth_png]))


def recording_seeds():
    # A one-sensor recording of 8x6 frames (fuzz_recording.cpp: profile.yaml is part 0).
    src = open(os.path.join(HERE, "..", "profiles", "single_kinect_kobuki.yaml"), "rb").read()
    profile = src.replace(b"width: 640", b"width: 8").replace(b"height: 480", b"height: 6")
    meta = (b"format: duet-recording\nversion: 1\nprofile: profile.yaml\nodometry: odometry.txt\n"
            b"sensors:\n  - {name: kinect, folder: s, width: 8, height: 6, depth_units_per_m: 1000}\n")
    odom = b"# stamp x y theta v omega arrival\n0 0 0 0 0 0 0.05\n0.02 0.001 0 0 0.05 0 0.05\n0.04 0.002 0 0.001 0.05 0.02 0.05\n"
    w, h = 8, 6
    colour = png(w, h, 3, 8, [b"".join(bytes([x & 255, y & 255, 90]) for x in range(w)) for y in range(h)])
    depth_rows = [b"".join(struct.pack(">H", 1000 + 2 * x + y if (x + y) % 5 else 0) for x in range(w)) for y in range(h)]
    depth_png = png(w, h, 1, 16, depth_rows)
    depth_txt = b"# stamp file arrival\n0 depth/000000.png 0.05\n"
    rgb_txt = b"# stamp file arrival\n0 rgb/000000.png 0.05\n"
    put("recording", "one_frame", SEP.join([profile, meta, odom, depth_txt, rgb_txt, depth_png, colour]))


def profile_seeds():
    src = open(os.path.join(HERE, "..", "profiles", "single_kinect_kobuki.yaml"), "rb").read()
    # The last line doubles as a --set overlay (fuzz_profile.cpp).
    put("profile", "set_speed", src + b"#exploration.view_range_m=3")
    put("profile", "set_bad", src + b"#mapping.grid_resolution_m=1e-9")
    minimal = (b"name: tiny\nchassis: {type: differential, radius_m: 0.2, wheel_base_m: 0.3, wheel_diameter_m: 0.07,"
               b" max_linear_speed_mps: 0.5, max_angular_speed_dps: 90, odometry_rate_hz: 50}\n"
               b"sensors:\n  - name: cam\n    intrinsics: {width: 64, height: 48, fov_h_deg: 57, fov_v_deg: 43}\n"
               b"    extrinsics: {xyz_m: [0.0, 0.0, 0.3], zyx_euler_deg: [0.0, 0.0, 0.0]}\n")
    put("profile", "minimal", minimal)


def capi_seeds():
    rng = random.Random(19)
    for i, n in enumerate((64, 256, 1024, 4096)):
        put("capi", "random%d" % i, bytes(rng.randrange(256) for _ in range(n)))
    # A scripted start: a device, a cloud, points, normals, a grid and an update, a planner
    # with a grid, a decision - then random bytes.
    script = bytes([0, 0, 2, 0, 2, 0, 3, 0, 0]) + bytes(rng.randrange(256) for _ in range(300))
    put("capi", "scripted", script)
    # A device, a runtime on the tiny profile, a simulator of the lab, then runtime and
    # simulator calls (fuzz_capi.cpp, cases 30 and 31) with random arguments.
    u32 = lambda v: struct.pack("<I", v)
    for k in range(2):
        run = u32(0) + bytes([0]) + u32(2)
        run += u32(0) + bytes([30]) + u32(1) + bytes([0, 1, 1, 0])
        run += u32(0) + bytes([30]) + u32(0) + bytes([2, 1, 3])
        for _ in range(24):
            run += u32(0) + bytes([31]) + u32(0) + u32(0) + bytes(rng.randrange(256) for _ in range(rng.randrange(4, 40)))
        put("capi", "runtime%d" % k, run)


def tum_seeds():
    """TUM trajectories: a short valid one, comments and blank lines, equal stamps, a
    quaternion to re-normalise, and broken lines (the reader names them)."""
    rows = ["%.4f %.3f %.3f %.3f 0 0 %.6f %.6f" % (0.1 * i, 0.1 * i, -0.05 * i, 0.0, math.sin(0.05 * i), math.cos(0.05 * i))
            for i in range(8)]
    put("tum", "valid.txt", ("# timestamp tx ty tz qx qy qz qw\n" + "\n".join(rows) + "\n").encode())
    put("tum", "comments.txt", ("\n# a comment\n\n" + rows[0] + "\n  \n" + rows[1] + "\n").encode())
    put("tum", "same_stamp.txt", (rows[2] + "\n" + rows[2].replace("0.200 ", "0.900 ", 1) + "\n" + rows[3] + "\n").encode())
    put("tum", "unnormalised.txt", b"1.0 0 0 0 0 0 0 1.005\n2.0 1 0 0 0 0 0.001 0.999\n3.0 2 0 0 0 0 0 1\n")
    put("tum", "broken.txt", b"1.0 0 0 0 0 0 0\n2.0 nan 0 0 0 0 0 1\n3.0 1e400 0 0 0 0 0 1\n")


if __name__ == "__main__":
    pcd_seeds()
    ply_seeds()
    map_seeds()
    world_seeds()
    rgbd_seeds()
    recording_seeds()
    profile_seeds()
    capi_seeds()
    tum_seeds()
