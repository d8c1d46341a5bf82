"""The original's magnetic_deformables_implicit with the magnet written in Python: 64 soft cubes
on a floor (μ 0.5 everywhere, contact thickness 5 mm) and a scripted magnet whose potential
−k/√(‖x − m‖² + ε²) acts on every node. The energy is a few lines of `starkrs.sym`; it is traced
once, differentiated and compiled, so the solve never calls Python. The magnet is lowered over
1.5–3 s and raised over 4.5–6 s by a time event that changes the energy's parameter `m`.

    python magnetic_deformables.py                  # 7 s, frames in output/magnetic_deformables
    python magnetic_deformables.py --duration 3 --cubes 4
    python magnetic_deformables.py --duration 0.5 --compare   # time against the Rust-defined scene
"""

import argparse
import math
import time

import starkrs
from starkrs import meshes, sym

STRENGTH_N_M2 = 1e-3  # k: at 0.1 m a node feels about twice its weight
SOFTENING_M = 0.01  # ε: keeps the potential finite at the magnet


def magnet_height_m(t):
    """0.6 m at rest, lowered to 0.15 m over 1.5–3 s, held, raised back over 4.5–6 s."""
    ramp = lambda t0, t1: min(max((t - t0) / (t1 - t0), 0.0), 1.0)  # noqa: E731
    return 0.6 + (0.15 - 0.6) * (ramp(1.5, 3.0) - ramp(4.5, 6.0))


def magnet(x, v, dt, p):
    """Energy of one node, J."""
    r = x[0] - p.m
    return -p.k / sym.sqrt(sym.dot(r, r) + p.softening_m**2)


def build(n, settings):
    sim = starkrs.Simulation(settings)
    floor_v, floor_t = meshes.triangle_grid((2.0, 2.0), (1, 1))
    floor = sim.add_prescribed_surface("floor", floor_v, floor_t, 0.005, 1e6)
    rubber = starkrs.VolumeMaterial.soft_rubber()
    rubber.strain.youngs_modulus = 2e4
    objects = [floor]
    for i in range(n):
        for j in range(n):
            centre = [(i - (n - 1) / 2) * 0.1, (j - (n - 1) / 2) * 0.1, 0.011 + 0.025]
            v, t = meshes.tet_grid([0.05] * 3, (2, 2, 2), centre)
            cube = sim.add_volume(f"cube{i * n + j}", v, t, rubber)
            for other in objects:
                sim.set_friction(cube, other, 0.5)
            objects.append(cube)
    params = {"k": STRENGTH_N_M2, "softening_m": SOFTENING_M, "m": [0.0, 0.0, magnet_height_m(0.0)]}
    energy = sim.add_energy("magnet", objects[1:], None, magnet, params)
    sim.add_time_event(0.0, math.inf, lambda s, t: s.set_energy_params(energy, {"m": [0.0, 0.0, magnet_height_m(t)]}))
    return sim, energy


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=7.0, help="simulated seconds (default: 7)")
    parser.add_argument("--cubes", type=int, default=8, help="cubes per side (default: 8, 64 cubes)")
    parser.add_argument("--out", default="output/magnetic_deformables", help="output directory")
    parser.add_argument("--no-frames", action="store_true", help="write no VTK frames")
    parser.add_argument("--compare", action="store_true",
                        help="also run the built-in scene (magnet written in Rust) and compare wall times")
    args = parser.parse_args(argv)

    settings = starkrs.Settings(name="magnetic_deformables")
    settings.time_step_s = 1.0 / 60.0
    settings.newton.residual_tolerance_n = 1e-6 * 60.0
    settings.newton.step_tolerance_m_s = 1e-3
    settings.contact.default_thickness_m = 0.005
    settings.output.directory = args.out
    settings.output.frames = not args.no_frames
    sim, energy = build(args.cubes, settings)
    trace_ms, diff_ms, compile_ms, _ = energy.compile_info
    start = time.perf_counter()
    summary = sim.run(args.duration)
    wall = time.perf_counter() - start
    cubes = sim.positions(sim.node_set("cube0"))
    print(f"{summary['steps']} steps, {summary['newton_iterations_per_step']:.1f} Newton iterations per step, "
          f"{wall:.2f} s wall; magnet traced in {trace_ms:.2f} ms, differentiated in {diff_ms:.2f} ms, "
          f"compiled in {compile_ms:.2f} ms; cube0 at height {cubes[:, 2].mean():.3f} m")
    if args.compare and args.cubes == 8:
        s = starkrs.Settings(name="magnetic_deformables_rust")
        s.output.directory = args.out
        s.output.frames = False
        s.output.step_log = False
        scene = starkrs.builtin_scene("magnetic_deformables", s)
        start = time.perf_counter()
        rs = scene.run(args.duration)
        rust_wall = time.perf_counter() - start
        print(f"built-in scene (magnet in Rust): {rs['steps']} steps, {rust_wall:.2f} s wall; "
              f"Python-defined / Rust-defined = {wall / rust_wall:.2f}")
    return sim


if __name__ == "__main__":
    main()
