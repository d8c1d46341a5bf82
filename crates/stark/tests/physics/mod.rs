//! The physics claims, one per file.

pub mod bad_input_gives_clear_errors;
pub mod cantilever_matches_linear_elasticity;
pub mod checks;
pub mod contact_scenes_never_intersect;
pub mod default_scene_converges_to_tolerance;
pub mod free_fall_matches_backward_euler;
pub mod incline_friction;
pub mod quasistatic_stretch_converges;
pub mod results_are_deterministic;
pub mod rigid_bodies_do_not_tunnel;
pub mod rigid_body_conserves_angular_momentum;
pub mod rigid_body_falls_like_backward_euler;
pub mod rigid_body_spins_stably_about_major_and_minor_axes;
pub mod rigid_box_incline_friction;
pub mod rigid_box_rests_on_soft_block;
pub mod rigid_box_stack_rests;
pub mod stark_replicas_match_reference;
