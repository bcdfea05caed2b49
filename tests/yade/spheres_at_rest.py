# YADE check of a mesopen target.spheres file: loaded as it is, nothing may move.
#
# Run by tests/yade/spheres_at_rest.sh as
#     yade -n -x spheres_at_rest.py FILE [--width W] [--radius-scale S]
# It loads FILE (comment lines '#', then "x y z r density" per grain, SI) with yade.ymport.text,
# holds the third dimension (no z motion, no rotation out of the x-y plane), adds the walls x = 0,
# x = W and y = 0 (top open), and runs 100 steps of a frictional linear-spring DEM with no gravity
# and no damping. Nothing pushes a grain but an overlap, so the largest speed measures the largest
# overlap. Prints "max_speed_m_per_s = V" and exits 0 if V < 1 m/s, 1 if not (the grains overlap),
# 2 on a malformed file.
#
# Tolerance: 1 m/s. A grain pressed into a neighbour (or a wall) by an overlap d swings at about
# d * omega, omega ~ sqrt(E / rho) / r ~ 1e8 rad/s for 20-40 um quartz-like grains, and 100 steps of
# half the P-wave time step (about 2e-7 s) cover several periods: 1 m/s flags overlaps of about
# 10 nm (0.03 % of a 30 um radius) and up (radii x 1.0001, overlaps of 3-6 nm, give 0.7 m/s).
# Touching disks (round-off overlaps, about 1e-19 m) stay near 1e-11 m/s; radii 15 % too large
# (--radius-scale 1.15, the negative control) give about 1000 m/s.
#
# Mass convention: the file's density is the grain's mass per metre over pi r^2 (a disk 1 m thick
# keeps the grain's mass). YADE has no disks: each grain becomes a sphere of the file's density,
# with its own FrictMat (so PWaveTimeStep sees it), mass rho 4/3 pi r^3 and inertia 2/5 m r^2 (what
# utils.sphere gives). A sphere and a disk of one material have the same omega up to a factor of
# order 1 (stiffness ~ E r against mass ~ rho r^3, per metre E against rho r^2), so the limit holds
# either way.
import argparse
import math
import os
import sys

from yade import ymport, utils
from yade.wrapper import (O, FrictMat, ForceResetter, InsertionSortCollider, Bo1_Sphere_Aabb,
                          Bo1_Wall_Aabb, InteractionLoop, Ig2_Sphere_Sphere_ScGeom,
                          Ig2_Wall_Sphere_ScGeom, Ip2_FrictMat_FrictMat_FrictPhys,
                          Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)
from yade.minieigenHP import Vector3

LIMIT = 1.0  # m/s
STEPS = 100
YOUNG = 70e9  # Pa, quartz-like
POISSON = 0.25  # ratio of tangential to normal stiffness in FrictPhys
FRICTION = math.atan(0.5)

parser = argparse.ArgumentParser(prog="spheres_at_rest.py")
parser.add_argument("file")
parser.add_argument("--width", type=float, default=None,
                    help="x of the right wall [m] (default: the largest x + r of the file)")
parser.add_argument("--radius-scale", type=float, default=1.0,
                    help="multiply every radius (a negative control: > 1 makes overlaps)")
args = parser.parse_args(sys.argv[1:])


def finish(status):
    # YADE makes /tmp/yade-XXXXXX (a fixed path, not $TMPDIR) at start and leaves it behind: remove
    # it if empty (nothing here writes to it).
    try:
        os.rmdir(os.path.dirname(O.tmpFilename()))
    except OSError:
        pass
    sys.exit(status)


# The density column, in the order ymport.text reads the spheres (it skips lines starting with '#').
rows = []
with open(args.file) as f:
    for n, line in enumerate(f, 1):
        cols = line.split()
        if not cols or cols[0].startswith("#"):
            continue
        if len(cols) != 5:
            print(f"{args.file}:{n}: expected 'x y z r density', got {len(cols)} columns")
            finish(2)
        rows.append([float(c) for c in cols])
if not rows:
    print(f"{args.file}: no spheres")
    finish(2)
if any(r[2] != 0.0 or r[3] <= 0.0 or r[4] <= 0.0 for r in rows):
    print(f"{args.file}: every sphere needs z = 0, r > 0 and density > 0")
    finish(2)
width = args.width if args.width is not None else max(r[0] + r[3] for r in rows)

wall_mat = O.materials.append(FrictMat(young=YOUNG, poisson=POISSON, frictionAngle=FRICTION,
                                       density=2650.0, label="walls"))
spheres = ymport.text(args.file, scale=1.0, material=wall_mat)
if len(spheres) != len(rows):
    print(f"{args.file}: ymport.text read {len(spheres)} spheres, the file has {len(rows)}")
    finish(2)
for b, row in zip(spheres, rows):
    # Same centre, radius scaled about it (ymport's own 'scale' would move the centres too).
    r = row[3] * args.radius_scale
    rho = row[4]
    b.shape.radius = r
    b.material = O.materials[O.materials.append(
        FrictMat(young=YOUNG, poisson=POISSON, frictionAngle=FRICTION, density=rho))]
    m = rho * 4.0 / 3.0 * math.pi * r**3
    b.state.mass = m
    b.state.inertia = Vector3(1, 1, 1) * (0.4 * m * r * r)
    b.state.blockedDOFs = "zXY"  # plane motion: x, y and the rotation about z only
ids = O.bodies.append(spheres)
O.bodies.append([
    utils.wall(0.0, axis=0, material=wall_mat),
    utils.wall(width, axis=0, material=wall_mat),
    utils.wall(0.0, axis=1, material=wall_mat),
])

O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_FrictPhys()],
        [Law2_ScGeom_FrictPhys_CundallStrack()],
    ),
    NewtonIntegrator(damping=0.0, gravity=(0, 0, 0)),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(STEPS, True)

fastest = max(ids, key=lambda i: O.bodies[i].state.vel.norm())
v = O.bodies[fastest].state.vel.norm()
b = O.bodies[fastest]
contacts = sum(1 for i in O.interactions if i.isReal)
print(f"{len(ids)} spheres (radius x {args.radius_scale:g}), walls x = 0, {width:.6g} m and y = 0; "
      f"dt = {O.dt:.3g} s, {STEPS} steps ({O.time:.3g} s), {contacts} contacts")
print(f"max_speed_m_per_s = {v:.6g} (body {fastest} at x = {b.state.pos[0]:.6g}, "
      f"y = {b.state.pos[1]:.6g}, r = {b.shape.radius:.3g})")
if not v < LIMIT:
    print(f"FAIL: a sphere moves at {v:.3g} m/s (limit {LIMIT:g} m/s): the spheres overlap each "
          f"other or a wall")
    finish(1)
print(f"OK: no sphere faster than {LIMIT:g} m/s")
finish(0)
