//! The physics claims, one per file.

pub mod bad_input_gives_clear_errors;
pub mod cantilever_matches_linear_elasticity;
pub mod checks;
pub mod contact_scenes_never_intersect;
pub mod default_scene_converges_to_tolerance;
pub mod free_fall_matches_backward_euler;
pub mod grasp_slips_at_mu_f;
pub mod incline_friction;
pub mod joint_rig;
pub mod joints_hold_their_load;
pub mod motor_lifts_and_stalls;
pub mod pendulum_period;
pub mod quasistatic_stretch_converges;
pub mod rb_point_chain_holds_its_joints;
pub mod results_are_deterministic;
pub mod rigid_attachment_carries_the_cloth;
pub mod rigid_bodies_do_not_tunnel;
pub mod rigid_body_conserves_angular_momentum;
pub mod rigid_body_falls_like_backward_euler;
pub mod rigid_body_spins_stably_about_major_and_minor_axes;
pub mod rigid_box_incline_friction;
pub mod rigid_box_rests_on_soft_block;
pub mod rigid_box_stack_rests;
pub mod servo_reaches_and_holds;
pub mod stark_replicas_match_reference;
pub mod velocity_controllers_cap_their_effort;
