"""Write a strongly graded Gmsh mesh for scaling studies (issue 16): the 10 mm square of
configs/plane_wave.toml, [0, 0.01]^2 (metres), with edges of H_MIN = 5 um at the point FOCUS
growing with the distance r from it as H_MIN + GROWTH r up to H_MAX = 1 mm: a 200:1 size range.
Physical curves "left", "right", "bottom", "top"; physical surface "plate". MSH 4.1 ASCII.

Usage: python3 scripts/graded_mesh.py OUT.msh   (requires the gmsh Python module: pip install gmsh)
"""

import sys

import gmsh

SIDE = 0.01
FOCUS = (0.0037, 0.0061)
H_MIN, H_MAX, GROWTH = 5e-6, 1e-3, 0.15

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("graded")
occ = gmsh.model.occ
square = occ.addRectangle(0.0, 0.0, 0.0, SIDE, SIDE)
focus = occ.addPoint(FOCUS[0], FOCUS[1], 0.0)
occ.synchronize()
gmsh.model.mesh.embed(0, [focus], 2, square)

sides = {"left": [], "right": [], "bottom": [], "top": []}
eps = 1e-3 * SIDE
for _, curve in gmsh.model.getBoundary([(2, square)], oriented=False):
    x, y, _ = occ.getCenterOfMass(1, curve)
    name = "left" if x < eps else "right" if x > SIDE - eps else "bottom" if y < eps else "top"
    sides[name].append(curve)
for name, curves in sides.items():
    gmsh.model.addPhysicalGroup(1, curves, name=name)
gmsh.model.addPhysicalGroup(2, [square], name="plate")

field = gmsh.model.mesh.field
distance = field.add("Distance")
field.setNumbers(distance, "PointsList", [focus])
size = field.add("MathEval")
field.setString(size, "F", f"min({H_MIN} + {GROWTH} * F{distance}, {H_MAX})")
field.setAsBackgroundMesh(size)
gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
gmsh.model.mesh.generate(2)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.option.setNumber("Mesh.Binary", 0)
gmsh.write(sys.argv[1])
gmsh.finalize()
