#!/usr/bin/env python3
"""Compares two map_server grids (duet's grid.yaml + grid.pgm, or map_server's) cell by cell in
the world frame: of the cells known (free or occupied) in both, the share in the same state, and
the known area of each. Usage: grid_agreement.py A.yaml B.yaml [--min-agreement F]
[--min-known-ratio F]; exits 1 when a minimum is not met. Prints one JSON line."""
import argparse
import json
import os
import sys


def read_map(yaml_path):
    meta = {}
    with open(yaml_path) as f:
        for line in f:
            if ":" in line:
                k, v = line.split(":", 1)
                meta[k.strip()] = v.strip()
    image = os.path.join(os.path.dirname(yaml_path), meta["image"])
    res = float(meta["resolution"])
    origin = [float(x) for x in meta["origin"].strip("[]").split(",")[:2]]
    negate = int(meta.get("negate", "0"))
    occ_t, free_t = float(meta.get("occupied_thresh", 0.65)), float(meta.get("free_thresh", 0.196))
    with open(image, "rb") as f:
        data = f.read()
    # P5 header: magic, width, height, maxval, separated by whitespace; '#' starts a comment line
    parts, pos = [], 0
    while len(parts) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        start = pos
        while not data[pos:pos + 1].isspace():
            pos += 1
        parts.append(data[start:pos])
    pos += 1
    if parts[0] != b"P5":
        raise ValueError(image + ": not a binary PGM")
    w, h, maxval = int(parts[1]), int(parts[2]), int(parts[3])
    pix = data[pos:pos + w * h]
    state = {}
    for r in range(h):
        y = h - 1 - r  # the image's top row is the map's largest y
        row = pix[r * w:(r + 1) * w]
        for x in range(w):
            v = row[x] / maxval
            p = v if negate else 1.0 - v
            if p > occ_t:
                state[(x, y)] = 1
            elif p < free_t:
                state[(x, y)] = 0
    return {"res": res, "origin": origin, "w": w, "h": h, "state": state}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--min-agreement", type=float, default=0.0)
    ap.add_argument("--min-known-ratio", type=float, default=0.0)
    args = ap.parse_args()
    A, B = read_map(args.a), read_map(args.b)
    same = both = 0
    for (x, y), s in A["state"].items():
        wx = A["origin"][0] + (x + 0.5) * A["res"]
        wy = A["origin"][1] + (y + 0.5) * A["res"]
        bx = int((wx - B["origin"][0]) // B["res"])
        by = int((wy - B["origin"][1]) // B["res"])
        t = B["state"].get((bx, by))
        if t is None:
            continue
        both += 1
        same += s == t
    known_a = len(A["state"]) * A["res"] ** 2
    known_b = len(B["state"]) * B["res"] ** 2
    out = {"known_a_m2": round(known_a, 3), "known_b_m2": round(known_b, 3), "known_in_both": both,
           "agreement": same / both if both else 0.0, "known_ratio": min(known_a, known_b) / max(known_a, known_b) if max(known_a, known_b) else 0.0}
    print(json.dumps(out))
    ok = out["agreement"] >= args.min_agreement and out["known_ratio"] >= args.min_known_ratio
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
