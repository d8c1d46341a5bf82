"""Inflation (after the original's inflation.py): a cloth held at its four corners is inflated
by a pressure ramped from 0 to its final value by changing the membrane parameters during the
run (`set_params` from a time event); it billows into a cushion.

    python inflation.py                     # 1 s, pressure ramped to 20 Pa over 0.5 s
    python inflation.py --duration 3 --pressure 100
"""

import argparse

import starkrs


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds (default: 1)")
    parser.add_argument("--pressure", type=float, default=20.0, help="final pressure, Pa (default: 20)")
    parser.add_argument("--ramp", type=float, default=0.5, help="ramp time, s (default: 0.5)")
    parser.add_argument("--out", default="output/inflation", help="output directory")
    parser.add_argument("--no-frames", action="store_true", help="write no VTK frames")
    args = parser.parse_args(argv)

    settings = starkrs.Settings(name="inflation", gravity_m_s2=[0.0, 0.0, 0.0])
    settings.output.directory = args.out
    settings.output.frames = not args.no_frames
    settings.newton.residual_tolerance_n = 1e-6 / settings.time_step_s
    settings.newton.step_tolerance_m_s = 1e-3
    sim = starkrs.Simulation(settings)

    cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [24, 24], starkrs.SurfaceMaterial.cotton_fabric())
    pin = starkrs.PrescribedParams(stiffness=1e6)
    for x in (-0.5, 0.5):
        for y in (-0.5, 0.5):
            sim.prescribe_in_box(cloth, [x, y, 0.0], [0.001] * 3, pin)

    def ramp(sim, t):
        params = sim.params(cloth.strain)
        params.inflation_pa = args.pressure * min(1.0, t / args.ramp)
        sim.set_params(cloth.strain, params)

    sim.add_time_event(0.0, float("inf"), ramp)
    summary = sim.run(args.duration)
    z = sim.positions(cloth)[:, 2]
    print(f"{summary['steps']} steps, {summary['newton_iterations_per_step']:.1f} Newton iterations per step, "
          f"pressure {sim.params(cloth.strain).inflation_pa:.1f} Pa, cushion height {z.max() - z.min():.3f} m, "
          f"{summary['wall_time_s']:.1f} s wall time")
    return sim


if __name__ == "__main__":
    main()
