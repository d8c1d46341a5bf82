"""Viscoelasticity (after the original's viscoelasticity.py): a slab of soft rubber with strong
strain-rate damping, its bottom held, is pressed by a torus that comes down and goes back up;
the dent recovers slowly.

The original moves a rigid torus with a scripted constraint; here the torus is a kinematic
obstacle (a prescribed surface) following the same script.

    python viscoelasticity.py                 # 1.5 s, 8 × 8 × 2 cells
    python viscoelasticity.py --duration 4 --cells 32 32 8
"""

import argparse

import starkrs
from starkrs import meshes


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.5, help="simulated seconds (default: 1.5)")
    parser.add_argument("--cells", type=int, nargs=3, default=[8, 8, 2], help="cells per side (default: 8 8 2)")
    parser.add_argument("--out", default="output/viscoelasticity", help="output directory")
    parser.add_argument("--no-frames", action="store_true", help="write no VTK frames")
    args = parser.parse_args(argv)

    thickness = 0.001
    settings = starkrs.Settings(name="viscoelasticity")
    settings.output.directory = args.out
    settings.output.frames = not args.no_frames
    settings.contact.default_thickness_m = thickness
    settings.newton.residual_tolerance_n = 1e-6 / settings.time_step_s
    settings.newton.step_tolerance_m_s = 1e-3
    sim = starkrs.Simulation(settings)

    size = [1.0, 1.0, 0.25]
    rubber = starkrs.VolumeMaterial.soft_rubber()
    rubber.strain.damping = 2e3  # strong strain-rate damping: the viscous part
    slab = sim.add_volume_grid("slab", size, args.cells, rubber)
    sim.prescribe_in_box(slab, [0.0, 0.0, -size[2] / 2], [1.01, 1.01, 0.001],
                         starkrs.PrescribedParams(stiffness=1e7, tolerance_m=0.005))

    vertices, triangles = meshes.torus_mesh(0.2, 0.06, 32, 12)
    top = size[2] / 2 + 0.06 + 3 * thickness
    torus = sim.add_prescribed_surface("torus", vertices + [0.0, 0.0, top], triangles, thickness, 1e6)

    def press(sim, t):
        # Down 0.1 m in 0.5 s, held for 0.25 s, back up in 0.5 s.
        depth = 0.1 * min(1.0, t / 0.5) if t < 0.75 else 0.1 * max(0.0, 1.0 - (t - 0.75) / 0.5)
        sim.set_transform(torus, [0.0, 0.0, -depth])

    sim.add_time_event(0.0, float("inf"), press)
    summary = sim.run(args.duration)
    top_nodes = sim.rest_positions(slab)[:, 2] > size[2] / 2 - 1e-9
    dent = size[2] / 2 - sim.positions(slab)[top_nodes, 2].min()
    print(f"{summary['steps']} steps, {summary['newton_iterations_per_step']:.1f} Newton iterations per step, "
          f"deepest point of the top surface {dent:.4f} m below rest, {summary['wall_time_s']:.1f} s wall time")
    return sim


if __name__ == "__main__":
    main()
