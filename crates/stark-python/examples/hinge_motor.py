"""A motor-driven crank: a wheel turned by a motor at 90°/s (at most 2 N·m) drives, through a
hinged connecting rod, a slider on a prismatic joint. Halfway through, a time event reverses the
motor from Python; the joint readouts (angle, rate, motor torque, slider position) are printed.

    python hinge_motor.py                  # 4 s, frames in output/hinge_motor
    python hinge_motor.py --duration 8
"""

import argparse
import math

import starkrs
from starkrs import meshes


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=4.0, help="simulated seconds (default: 4)")
    parser.add_argument("--out", default="output/hinge_motor", help="output directory")
    parser.add_argument("--no-frames", action="store_true", help="write no VTK frames")
    args = parser.parse_args(argv)

    settings = starkrs.Settings(name="hinge_motor")
    settings.time_step_s = 0.01
    settings.output.directory = args.out
    settings.output.frames = not args.no_frames
    sim = starkrs.Simulation(settings)

    # Wheel (crank) in the xz plane turning about y at the origin; crank pin 0.1 m out on +x.
    wheel = sim.add_rigid_body_with("wheel", starkrs.MassProperties.cylinder(1.0, 0.12, 0.02), [0.0, 0.0, 0.0],
                                    [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0])
    v, t = meshes.cylinder_mesh(0.12, 0.02, 24, 1)
    sim.add_rigid_output_mesh(wheel, v, t)
    # Connecting rod from the crank pin (0.1, 0, 0) to the slider at (0.4, 0, 0).
    rod = sim.add_rigid_body_with("rod", starkrs.MassProperties.cuboid(0.2, [0.3, 0.02, 0.02]), [0.25, 0.0, 0.0])
    v, t = meshes.box_mesh([0.3, 0.02, 0.02])
    sim.add_rigid_output_mesh(rod, v, t)
    slider = sim.add_rigid_body_with("slider", starkrs.MassProperties.cuboid(0.5, [0.06] * 3), [0.4, 0.0, 0.0])
    v, t = meshes.box_mesh([0.06] * 3)
    sim.add_rigid_output_mesh(slider, v, t)

    motor = sim.add_motor("motor", None, wheel, [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], math.radians(90.0), 2.0)
    sim.add_hinge_joint("crank_pin", wheel, rod, [0.1, 0.0, 0.0], [0.0, 1.0, 0.0])
    sim.add_hinge_joint("wrist_pin", rod, slider, [0.4, 0.0, 0.0], [0.0, 1.0, 0.0])
    guide = sim.add_prismatic_joint("guide", None, slider, [0.4, 0.0, 0.0], [1.0, 0.0, 0.0])

    def reverse(sim, t):
        sim.set_joint_target_velocity(motor, -math.radians(90.0))

    sim.add_time_event(args.duration / 2, math.inf, reverse)
    summary = sim.run(args.duration)
    m, g = sim.joint_state(motor), sim.joint_state(guide)
    print(f"{summary['steps']} steps, {summary['newton_iterations_per_step']:.1f} Newton iterations per step: "
          f"motor at {math.degrees(m.coordinate):.1f}° turning {math.degrees(m.coordinate_rate):.1f}°/s "
          f"with {m.driver_effort:.3f} N·m, slider at {g.coordinate * 1000:.1f} mm, "
          f"largest joint violation {sim.max_joint_violations()[0]:.1e} m")
    return sim


if __name__ == "__main__":
    main()
