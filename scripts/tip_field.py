#!/usr/bin/env python3
"""The effective traction around a point of a snapshot, on circles of given radii.

Reads a `snapshot_NNNN.vtu` written by `sdg run` (binary or ASCII), and for each radius r prints,
every 5 degrees of the direction theta from the point (x, y), the effective traction
`sqrt(<sn>_+^2 + beta^2 st^2)` and the normal traction `sn` (MPa) on the plane through the point
along theta, with the stress at distance r along theta: the seed's propagation test (4.3.2)
"at a finite distance" from a crack tip instead of at radius 0+. Points where the slice has no
triangle (outside the domain) print `--`; on a crack face the two sides are averaged.

Usage: python3 scripts/tip_field.py SNAPSHOT.vtu X_M Y_M R_UM[,R_UM...] [BETA]
Needs numpy (`pip install numpy`).
"""
import base64
import re
import struct
import sys
import zlib

import numpy as np

TYPES = {"Float64": "<f8", "Float32": "<f4", "UInt32": "<u4", "Int32": "<i4",
         "UInt64": "<u8", "Int64": "<i8", "UInt8": "u1"}


def arrays(path):
    """The named DataArrays of a VTK XML file (points under `points`)."""
    text = open(path).read()
    found = {}
    pattern = r'<DataArray type="(\w+)"([^>]*)format="(\w+)">\n(.*?)</DataArray>'
    points = text.index("<Points>")
    for m in re.finditer(pattern, text, re.S):
        ty, attrs, fmt, body = m.groups()
        name = re.search(r'Name="([^"]+)"', attrs)
        if name:
            key = name.group(1)
        elif points < m.start() < text.index("</Points>"):
            key = "points"
        else:
            continue
        dtype = TYPES[ty]
        if fmt == "ascii":
            values = np.array(body.split(), dtype=float).astype(dtype)
        else:
            body = body.strip()
            blocks = struct.unpack("<Q", base64.b64decode(body[:32])[:8])[0]
            chars = (8 * (3 + blocks) + 2) // 3 * 4
            header = np.frombuffer(base64.b64decode(body[:chars]), "<u8")
            data = base64.b64decode(body[chars:])
            raw, offset = b"", 0
            for size in header[3:3 + blocks]:
                raw += zlib.decompress(data[offset:offset + int(size)])
                offset += int(size)
            values = np.frombuffer(raw, dtype)
        components = re.search(r'NumberOfComponents="(\d+)"', attrs)
        if components:
            values = values.reshape(-1, int(components.group(1)))
        found[key] = values
    return found


def main():
    if len(sys.argv) not in (5, 6):
        sys.exit(__doc__)
    path, x, y = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    radii = [float(r) * 1e-6 for r in sys.argv[4].split(",")]
    beta = float(sys.argv[5]) if len(sys.argv) == 6 else 1.0
    data = arrays(path)
    corners = data["points"][:, :2].reshape(-1, 3, 2)
    stress = data["stress"].reshape(-1, 3, 6)
    near = np.abs(corners.mean(axis=1) - [x, y]).max(axis=1) < 2 * max(radii) + 1e-4
    corners, stress = corners[near], stress[near]

    def cross(u, v):
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    area = cross(b - a, c - a)

    def stress_at(p):
        lb = cross(p - a, c - a) / area
        lc = cross(b - a, p - a) / area
        la = 1.0 - lb - lc
        inside = (la >= -1e-9) & (lb >= -1e-9) & (lc >= -1e-9)
        if not inside.any():
            return None
        i = np.nonzero(inside)[0]
        values = la[i, None] * stress[i, 0] + lb[i, None] * stress[i, 1] + lc[i, None] * stress[i, 2]
        return values.mean(axis=0)

    for r in radii:
        print(f"r = {r * 1e6:g} um: theta (deg): effective / normal traction (MPa)")
        cells = []
        for degrees in range(-180, 180, 5):
            theta = np.radians(degrees)
            s = stress_at(np.array([x + r * np.cos(theta), y + r * np.sin(theta)]))
            if s is None:
                cells.append(f"{degrees:4d}:    --    ")
                continue
            m = np.array([[s[0], s[3]], [s[3], s[1]]])
            normal = np.array([-np.sin(theta), np.cos(theta)])
            along = np.array([np.cos(theta), np.sin(theta)])
            sn, st = normal @ m @ normal, along @ m @ normal
            cells.append(f"{degrees:4d}:{np.hypot(max(sn, 0.0), beta * st) * 1e-6:5.0f}/{sn * 1e-6:4.0f}")
        for i in range(0, len(cells), 8):
            print("  ".join(cells[i:i + 8]))


if __name__ == "__main__":
    main()
