"""Twisting cloth (the original's): a 0.5 m cloth standing in the XZ plane, its two side edges
turned in opposite directions at 90°/s about the X axis, without gravity. The cloth wrings
itself into a rope held apart only by self-contact (thickness 1 mm, self-friction μ = 1).

    python twisting_cloth.py                          # 1 s, 32 × 32
    python twisting_cloth.py --duration 5 --quads 64  # the original's run
"""

import argparse
import math

import numpy as np

import starkrs
from starkrs import meshes


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds (default: 1)")
    parser.add_argument("--quads", type=int, default=32, help="quads per side (default: 32)")
    parser.add_argument("--out", default="output/twisting_cloth", help="output directory")
    parser.add_argument("--no-frames", action="store_true", help="write no VTK frames")
    args = parser.parse_args(argv)

    settings = starkrs.Settings(name="twisting_cloth", gravity_m_s2=[0.0, 0.0, 0.0])
    settings.output.directory = args.out
    settings.output.frames = not args.no_frames
    settings.contact.default_thickness_m = 0.001
    settings.contact.hessian = "gauss_newton"  # cheap PSD barrier Hessian for many light pairs
    settings.newton.residual_tolerance_n = 1e-6 / settings.time_step_s
    settings.newton.step_tolerance_m_s = 1e-3
    sim = starkrs.Simulation(settings)

    cotton = starkrs.SurfaceMaterial.cotton_fabric()
    cotton.strain.damping = 0.0  # elasticity only, as in the original
    cotton.strain.strain_limit = math.inf
    vertices, triangles = meshes.triangle_grid([0.5, 0.5], [args.quads, args.quads])
    vertices = vertices[:, [0, 2, 1]] * [1.0, -1.0, 1.0]  # the XY grid turned 90° about X
    cloth = sim.add_surface("cloth", vertices, triangles, cotton)
    sim.set_friction(cloth, cloth, 1.0)

    for x, sign in [(-0.25, 1.0), (0.25, -1.0)]:
        edge = sim.prescribe_in_box(cloth, [x, 0.0, 0.0], [0.001, 0.5, 0.5])

        def twist(sim, t, edge=edge, sign=sign):
            sim.set_transform_deg(edge, [0.0, 0.0, 0.0], sign * 90.0 * t, [1.0, 0.0, 0.0])

        sim.add_time_event(0.0, math.inf, twist)

    summary = sim.run(args.duration)
    x = sim.positions(cloth)
    radius = np.sqrt(x[:, 1] ** 2 + x[:, 2] ** 2)
    print(f"{summary['steps']} steps, {summary['newton_iterations_per_step']:.1f} Newton iterations per step, "
          f"{summary['max_active_pairs']} contact pairs at most, largest distance from the axis {radius.max():.3f} m, "
          f"{summary['wall_time_s']:.1f} s wall time")
    return sim


if __name__ == "__main__":
    main()
