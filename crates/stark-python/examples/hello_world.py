"""Hello world (the original Stark's): a 0.4 m cotton cloth falls onto a box that spins at
90°/s and bobs up and down; the cloth drapes over it with self-contact.

As in the original, the box is a 1 kg rigid body driven by a fix joint whose target pose is
set every step from a time event.

    python hello_world.py                  # 1 s, frames in output/hello_world
    python hello_world.py --duration 10    # the original's 10 s
"""

import argparse
import math

import starkrs


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds (default: 1)")
    parser.add_argument("--out", default="output/hello_world", help="output directory")
    parser.add_argument("--no-frames", action="store_true", help="write no VTK frames")
    args = parser.parse_args(argv)

    settings = starkrs.Settings(name="hello_world")
    settings.output.directory = args.out
    settings.output.frames = not args.no_frames
    settings.contact.default_thickness_m = 0.0025
    settings.newton.residual_tolerance_n = 1e-6 / settings.time_step_s  # the original's criteria
    settings.newton.step_tolerance_m_s = 1e-3
    sim = starkrs.Simulation(settings)

    cloth = sim.add_surface_grid("cloth", [0.4, 0.4], [32, 32], starkrs.SurfaceMaterial.cotton_fabric())
    box = sim.add_box("box", 1.0, [0.08, 0.08, 0.08], [0.0, 0.0, -0.08])
    drive = sim.add_fix_joint("box_drive", box)

    def move_box(sim, t):
        sim.set_fixed_transform_deg(drive, [0.0, 0.0, -0.08 - 0.1 * math.sin(t)], 90.0 * t, [0.0, 0.0, 1.0])

    sim.add_time_event(0.0, math.inf, move_box)
    summary = sim.run(args.duration)
    z = sim.positions(cloth)[:, 2]
    print(f"{summary['steps']} steps, {summary['newton_iterations_per_step']:.1f} Newton iterations per step, "
          f"cloth z in [{z.min():.3f}, {z.max():.3f}] m, {summary['wall_time_s']:.1f} s wall time")
    return sim


if __name__ == "__main__":
    main()
