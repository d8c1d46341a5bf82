"""Boxes on cloth (after the original's boxes_on_cloth.py): rigid boxes dropped in a stack onto a
cloth held at two opposite edges; the cloth sags under them, then its edges are lifted and pulled
sideways and the boxes slide and tumble. Friction 0.5 everywhere.

    python boxes_on_cloth.py                  # 1.5 s
    python boxes_on_cloth.py --duration 6 --boxes 8
"""

import argparse
import math

import numpy as np

import starkrs
from starkrs import meshes


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.5, help="simulated seconds (default: 1.5)")
    parser.add_argument("--boxes", type=int, default=4, help="number of stacked boxes (default: 4)")
    parser.add_argument("--out", default="output/boxes_on_cloth", help="output directory")
    parser.add_argument("--no-frames", action="store_true", help="write no VTK frames")
    args = parser.parse_args(argv)

    thickness = 0.001
    settings = starkrs.Settings(name="boxes_on_cloth")
    settings.output.directory = args.out
    settings.output.frames = not args.no_frames
    settings.contact.default_thickness_m = thickness
    settings.newton.residual_tolerance_n = 1e-6 / settings.time_step_s
    settings.newton.step_tolerance_m_s = 1e-3
    sim = starkrs.Simulation(settings)

    cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [24, 24], starkrs.SurfaceMaterial.cotton_fabric())
    pin = starkrs.PrescribedParams(stiffness=1e6)
    edges = [sim.prescribe_in_box(cloth, [x, 0.0, 0.0], [0.001, 1.001, 0.001], pin) for x in (-0.5, 0.5)]

    size = 0.1
    vertices, triangles = meshes.box_mesh([size] * 3)
    contacts = [cloth.contact]
    bodies = []
    for k in range(args.boxes):
        angle = 0.4 * k
        orientation = [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]  # (w, x, y, z) about z
        center = [0.02 * k, 0.0, size / 2 + 2 * thickness + (size + 3 * thickness) * k]
        body = sim.add_rigid_body_with(f"box{k}", starkrs.MassProperties.cuboid(0.05, [size] * 3), center, orientation)
        mesh = sim.add_rigid_collision_mesh(body, vertices, triangles, thickness)
        for other in contacts:
            sim.set_friction(mesh, other, 0.5)
        contacts.append(mesh.contact)
        bodies.append(body)

    def lift_and_pull(sim, t):
        # From 1 s on, both edges rise at 5 cm/s and the whole cloth moves in +y at 10 cm/s.
        tau = t - 1.0
        for edge in edges:
            sim.set_transform(edge, [0.0, 0.1 * tau, 0.05 * tau])

    sim.add_time_event(1.0, math.inf, lift_and_pull)
    summary = sim.run(args.duration)
    heights = [sim.body_position(b)[2] for b in bodies]
    print(f"{summary['steps']} steps, {summary['newton_iterations_per_step']:.1f} Newton iterations per step, "
          f"box heights {np.round(heights, 3).tolist()} m, {summary['wall_time_s']:.1f} s wall time")
    return sim


if __name__ == "__main__":
    main()
