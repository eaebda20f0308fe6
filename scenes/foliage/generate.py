#!/usr/bin/env python3
"""Writes the foliage set (issue 61): bushes of leaf cards, each card's leaf a cutout of about
half its square that lets a third of its diffuse light through (diffuse transmission), instanced over a ground, with a fence of cutout slats, under a sun and a sky.
Deterministic: the same files every run. Usage: generate.py [FOLDER] (default: this folder)."""
import json, math, os, random, struct, sys, zlib

def png_grey(path, w, h, value):
    """An 8-bit grey PNG of value(x, y) in [0, 1] (x, y at texel centres, y down)."""
    rows = b"".join(b"\x00" + bytes(int(round(255 * max(0.0, min(1.0, value((x + 0.5) / w, (y + 0.5) / h)))))
                                     for x in range(w)) for y in range(h))
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))

def leaf(u, v):
    """A pointed leaf along the card's diagonal-free vertical axis: two arcs meeting at its tips."""
    x, y = 2 * u - 1, 2 * v - 1          # [-1, 1]^2
    half_width = 0.82 * (1 - y * y)      # widest at the middle, zero at the tips
    return 1.0 if abs(x) <= half_width else 0.0

def slats(u, v):
    """A fence panel: five vertical slats with gaps between (half of it open)."""
    return 1.0 if (u * 5) % 1.0 < 0.5 else 0.0

def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    png_grey(os.path.join(folder, "leaf.png"), 64, 64, leaf)
    png_grey(os.path.join(folder, "slats.png"), 64, 8, slats)
    rng = random.Random(61)
    cards = []
    bushes = [(-3.2, 2.5, 1.1), (-0.6, 3.6, 1.4), (2.4, 2.2, 1.0), (4.6, 4.4, 1.3), (-5.0, 5.2, 1.2), (0.9, 0.6, 0.7)]
    for bx, bz, r in bushes:
        for _ in range(int(420 * r * r)):
            # A point in the bush's ellipsoid, the card turned at random about a random axis.
            while True:
                p = [rng.uniform(-1, 1) for _ in range(3)]
                if sum(c * c for c in p) <= 1: break
            axis = [rng.gauss(0, 1) for _ in range(3)]
            cards.append({"translate": [round(bx + r * p[0], 4), round(r * (1.0 + 0.8 * p[1]), 4), round(bz + r * p[2], 4)],
                          "rotate": [round(rng.uniform(0, 360), 2)] + [round(a, 4) for a in axis]})
    scene = {
        "camera": {"position": [0.5, 1.7, -7.5], "look_at": [0, 1.2, 2.5], "fov": 55, "resolution": [640, 360]},
        "render": {"spp": 4, "rays": 256, "gi": "cache"},
        "materials": {
            "ground": {"color": [0.35, 0.3, 0.22]},
            "leaf": {"color": [0.18, 0.42, 0.08], "alpha_mode": "mask", "opacity_texture": "leaf.png",
                     "diffuse_transmission": 0.35, "diffuse_transmission_color": [0.45, 0.7, 0.15]},
            "wood": {"color": [0.55, 0.45, 0.35], "alpha_mode": "mask", "opacity_texture": "slats.png"},
            "wall": {"color": 0.7},
        },
        "lights": [{"type": "distant", "direction": [-0.4, -0.8, 0.45], "color": [3.0, 2.8, 2.5]},
                   {"type": "sky", "color": [0.25, 0.32, 0.45]}],
        "objects": [
            {"name": "ground", "type": "quad", "material": "ground", "vertices": [[-30, 0, -30], [-30, 0, 30], [30, 0, 30], [30, 0, -30]]},
            {"name": "wall", "type": "quad", "material": "wall", "vertices": [[-12, 0, 7], [12, 0, 7], [12, 5, 7], [-12, 5, 7]]},
            {"name": "fence", "type": "quad", "material": "wood", "vertices": [[-7, 0, 0.2], [-2, 0, 0.2], [-2, 1.2, 0.2], [-7, 1.2, 0.2]]},
            {"name": "card", "type": "quad", "material": "leaf", "prototype": True,
             "vertices": [[-0.09, -0.14, 0], [0.09, -0.14, 0], [0.09, 0.14, 0], [-0.09, 0.14, 0]]},
            {"name": "leaves", "instances": {"of": "card", "transforms": cards}},
        ],
    }
    with open(os.path.join(folder, "foliage.json"), "w") as f:
        json.dump(scene, f, separators=(",", ":"))
        f.write("\n")
    print(f"{len(cards)} leaf cards")

if __name__ == "__main__":
    main()
