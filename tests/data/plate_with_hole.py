"""Generate the Gmsh test meshes next to this script.

plate_with_hole.msh: a 4 mm x 4 mm square plate [0, 0.004] x [0, 0.004] (metres) with a
centred circular hole of radius 1 mm, mesh size about 0.4 mm. Physical curves "left",
"right", "bottom", "top" and "hole"; physical surface "plate". Saved as MSH 4.1 ASCII.

truncated.msh: the same file cut in the middle of its $Elements section (the first half of the
element lines are kept, the rest of the file is dropped), to test the reader's error on a
truncated file.

Rerun with `python3 tests/data/plate_with_hole.py`; requires the gmsh Python module.
"""

import os

import gmsh

SIDE = 0.004
RADIUS = 0.001
SIZE = 0.0004

here = os.path.dirname(os.path.abspath(__file__))
msh_path = os.path.join(here, "plate_with_hole.msh")
truncated_path = os.path.join(here, "truncated.msh")

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("plate_with_hole")
occ = gmsh.model.occ
square = occ.addRectangle(0.0, 0.0, 0.0, SIDE, SIDE)
disk = occ.addDisk(SIDE / 2, SIDE / 2, 0.0, RADIUS, RADIUS)
plate, _ = occ.cut([(2, square)], [(2, disk)])
occ.synchronize()

sides = {"left": [], "right": [], "bottom": [], "top": [], "hole": []}
eps = 1e-3 * SIDE
for _, curve in gmsh.model.getBoundary(plate, oriented=False):
    x, y, _ = occ.getCenterOfMass(1, curve)
    if x < eps:
        sides["left"].append(curve)
    elif x > SIDE - eps:
        sides["right"].append(curve)
    elif y < eps:
        sides["bottom"].append(curve)
    elif y > SIDE - eps:
        sides["top"].append(curve)
    else:
        sides["hole"].append(curve)
for name, curves in sides.items():
    assert curves, f"no curve found for side {name}"
    gmsh.model.addPhysicalGroup(1, curves, name=name)
gmsh.model.addPhysicalGroup(2, [tag for _, tag in plate], name="plate")

gmsh.option.setNumber("Mesh.MeshSizeMin", SIZE)
gmsh.option.setNumber("Mesh.MeshSizeMax", SIZE)
gmsh.model.mesh.generate(2)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.option.setNumber("Mesh.Binary", 0)
gmsh.write(msh_path)
gmsh.finalize()

with open(msh_path) as f:
    lines = f.read().splitlines(keepends=True)
start = lines.index("$Elements\n")
end = lines.index("$EndElements\n")
with open(truncated_path, "w") as f:
    f.writelines(lines[: (start + end) // 2])

print(f"wrote {msh_path} and {truncated_path}")
