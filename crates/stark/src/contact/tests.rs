//! Tests across the stages: validity of trial states and the Hessian switch.

use crate::energy::kinematics::BodyPose;
use crate::energy::EnergyTerm;
use crate::presets::ObstacleHandle;
use crate::state::{dof_blocks, EvalState};
use crate::{Settings, Simulation};
use nalgebra::{UnitQuaternion, Vector3};

fn square(z: f64, half: f64) -> [Vector3<f64>; 4] {
    [
        Vector3::new(-half, -half, z),
        Vector3::new(half, -half, z),
        Vector3::new(half, half, z),
        Vector3::new(-half, half, z),
    ]
}

/// Run the contact term's `before_step` at the current state and return the validity of the
/// positions `x` through `is_valid_state`.
fn valid_at(sim: &mut Simulation, x: &[Vector3<f64>]) -> bool {
    at_rest(sim, |contact, state| {
        contact.before_step(state);
        let trial = EvalState { x, ..*state };
        contact.is_valid_state(&trial)
    })
}

/// Call `f` with the contact term and the state of the simulation at rest (dt = 0.01 s).
fn at_rest<R>(sim: &mut Simulation, f: impl FnOnce(&mut super::Contact, &EvalState) -> R) -> R {
    let zeros = vec![Vector3::zeros(); dof_blocks(&sim.nodes, &sim.bodies)];
    let poses: Vec<BodyPose> = (0..sim.bodies.len())
        .map(|b| BodyPose::at_rest(sim.bodies.position[b], &sim.bodies.orientation[b], 0.01))
        .collect();
    let nodes = sim.nodes.clone();
    let state = EvalState {
        dt: 0.01,
        time: 0.01,
        gravity: Vector3::zeros(),
        nodes: &nodes,
        v: &zeros,
        x: &nodes.x,
        bodies: &sim.bodies,
        poses: &poses,
    };
    f(&mut sim.contact, &state)
}

#[test]
fn trial_states_with_rigid_crossings_are_invalid() {
    let mut settings = Settings::default();
    settings.contact.default_thickness_m = Some(1e-3);
    let mut sim = Simulation::new(settings).unwrap();
    // A 2 m sheet whose diagonal runs from (−1, −1) to (1, 1), and two 0.1 m boxes above
    // it, far from the diagonal and the border.
    let sheet = sim
        .add_prescribed_surface("sheet", &square(0.0, 1.0), &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e4)
        .unwrap();
    let (q, size) = (UnitQuaternion::identity(), Vector3::repeat(0.1));
    let a = sim
        .add_box("a", 1.0, size, Vector3::new(0.5, -0.5, 0.1), q, None)
        .unwrap();
    let b = sim
        .add_box("b", 1.0, size, Vector3::new(-0.5, 0.5, 0.1), q, None)
        .unwrap();
    let x = sim.nodes.x.clone();
    assert!(valid_at(&mut sim, &x));
    // Box a straddles the sheet: only its vertical edges cross a sheet triangle.
    let mut down = x.clone();
    for i in a.mesh.nodes.range() {
        down[i].z -= 0.1;
    }
    assert!(!valid_at(&mut sim, &down));
    // Box a overlaps box b (rigid–rigid).
    let mut over = x.clone();
    for i in a.mesh.nodes.range() {
        over[i] += Vector3::new(-0.95, 0.95, 0.03);
    }
    assert!(!valid_at(&mut sim, &over));
    // Box a centred on the sheet's diagonal: the diagonal crosses its faces.
    let mut moved = x.clone();
    for i in a.mesh.nodes.range() {
        moved[i] += Vector3::new(-0.5, -0.5, -0.1);
    }
    assert!(!valid_at(&mut sim, &moved));
    // Pairs whose collisions are off are not tested.
    sim.contact.disable_collision(sheet.contact, a.mesh.contact).unwrap();
    assert!(valid_at(&mut sim, &down));
    let _ = b;
}

/// A simulation of two prescribed triangles (1 mm contact thickness, 1 g per node for the
/// barrier stiffness).
fn two_prescribed_triangles(lower: [Vector3<f64>; 3], upper: [Vector3<f64>; 3]) -> Simulation {
    let mut settings = Settings::default();
    settings.contact.default_thickness_m = Some(1e-3);
    let mut sim = Simulation::new(settings).unwrap();
    sim.add_prescribed_surface("lower", &lower, &[[0, 1, 2]], 1e-3, 1e4)
        .unwrap();
    sim.add_prescribed_surface("upper", &upper, &[[0, 1, 2]], 1e-3, 1e4)
        .unwrap();
    let masses_kg = vec![1e-3; sim.nodes.len()];
    sim.contact.initialize_stiffness(&masses_kg, 0.01, 9.81);
    sim
}

/// Two triangles whose corners face each other 0.4 mm apart: one point–point pair.
fn facing_corners() -> Simulation {
    let lower = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(-1.0, 0.0, -1.0),
        Vector3::new(0.0, -1.0, -1.0),
    ];
    let upper = lower.map(|p| Vector3::new(-p.x, -p.y, 4e-4 - p.z));
    two_prescribed_triangles(lower, upper)
}

/// Newton's `use_definite_hessian` switch: on (far from the solution), a pair whose distance
/// curves assembles a positive semi-definite Hessian; off (near it), the exact one, whose
/// negative curvature across the pair the inertia carries.
#[test]
fn barrier_pairs_take_their_exact_hessian_when_newton_asks() {
    use crate::energy::psd::symmetric_eigen;
    use crate::energy::EvalMode;
    let mut sim = facing_corners();
    let x = sim.nodes.x.clone();
    assert!(valid_at(&mut sim, &x));
    at_rest(&mut sim, |contact, state| {
        contact.prepare_evaluation(state);
        // The corners' point–point pair, and the edges that meet there (edge–edge, the same
        // closest points).
        let pairs = contact.pairs().len();
        assert!(pairs >= 1);
        let mut smallest_eigenvalue = |e: usize, definite: bool| {
            contact.use_definite_hessian(definite);
            let mut out = vec![0.0; crate::energy::term::element_stride(4)];
            contact.evaluate_element(e, state, EvalMode::ExactHessian, &mut out);
            // The 12×12 Hessian from its 3×3 blocks.
            let mut h = [0.0; 144];
            for (a, b, i, j) in hessian_block_entries() {
                h[(3 * a + i) * 12 + 3 * b + j] = out[13 + 9 * (a * 4 + b) + 3 * i + j];
            }
            let (mut w, mut v) = ([0.0; 12], [0.0; 144]);
            symmetric_eigen(&h, 12, &mut w, &mut v);
            let scale = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            w.iter().copied().fold(f64::INFINITY, f64::min) / scale
        };
        for e in 0..pairs {
            let l = smallest_eigenvalue(e, true);
            assert!(l > -1e-12, "definite form: pair {e}: {l}");
        }
        let exact = (0..pairs).map(|e| smallest_eigenvalue(e, false));
        assert!(
            exact.fold(f64::INFINITY, f64::min) < -1e-3,
            "exact: negative curvature across"
        );
    });
}

/// A pair reached from several candidates is one pair counting them: two triangles whose
/// corners face each other give the corners' point–point pair from both point–triangle
/// candidates and from the two edge–edge candidates of non-parallel edges there (the parallel
/// ones are mollified edge–edge pairs of their own).
#[test]
fn a_pair_reached_from_several_candidates_is_one_pair() {
    use super::pairs::PairKind;
    let mut sim = facing_corners();
    at_rest(&mut sim, |contact, state| {
        contact.prepare_evaluation(state);
        let pairs = contact.pairs();
        let mut keys: Vec<_> = pairs.iter().map(|p| (p.kind, p.nodes)).collect();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), pairs.len(), "each pair once: {keys:?}");
        let corners: Vec<_> = pairs.iter().filter(|p| p.kind == PairKind::PointPoint).collect();
        assert_eq!(corners.len(), 1);
        assert_eq!(corners[0].multiplicity, 4.0);
        let mollified = pairs
            .iter()
            .filter(|p| matches!(p.kind, PairKind::EdgeEdgeMollified(_)));
        assert_eq!(mollified.count(), 2);
    });
}

/// (block row, block column, row, column) of the 4×4 blocks of 3×3 in an element buffer.
fn hessian_block_entries() -> impl Iterator<Item = (usize, usize, usize, usize)> {
    (0..4).flat_map(|a| (0..4).flat_map(move |b| (0..3).flat_map(move |i| (0..3).map(move |j| (a, b, i, j)))))
}

#[test]
fn deformable_crossings_are_left_to_ccd_and_scenes_without_bodies_pay_nothing() {
    let mut settings = Settings::default();
    settings.contact.default_thickness_m = Some(1e-3);
    let mut sim = Simulation::new(settings).unwrap();
    sim.add_prescribed_surface("lower", &square(0.0, 1.0), &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e4)
        .unwrap();
    sim.add_prescribed_surface("upper", &square(0.5, 0.5), &[[0, 1, 2], [0, 2, 3]], 1e-3, 1e4)
        .unwrap();
    let mut x = sim.nodes.x.clone();
    // The upper sheet tilted through the lower one.
    x[4].z = -0.5;
    x[5].z = -0.5;
    assert!(!sim.contact.find_intersections(&x).is_empty());
    assert!(valid_at(&mut sim, &x), "deformable pairs are CCD's business");
    assert!(sim.contact.rigid_split.is_empty());
    assert_eq!(sim.contact.validity_record.0, 0, "no test ran");
}

/// An `n × n` grid of squares (two triangles each), `size` wide at height `z`, slightly
/// wavy so that its vertices meet the other grid's triangles, edges and vertices.
fn wavy_grid(n: usize, size: f64, z: f64, phase: f64) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
    let h = size / n as f64;
    let mut x = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f64 * h, j as f64 * h);
            let wave = 2e-4 * (7.0 * u + phase).sin() * (5.0 * v).cos();
            x.push(Vector3::new(u + phase * 0.3 * h, v + phase * 0.2 * h, z + wave));
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (x, t)
}

/// Two `n × n` wavy grids `size` wide, prescribed, 1.2 mm apart with the upper one shifted
/// (1 mm contact thickness: their vertices, edges and triangles all within d̂); the handles and
/// the lower grid's node count (its nodes come first).
fn stacked_wavy_grids(n: usize, size: f64) -> (Simulation, ObstacleHandle, ObstacleHandle, usize) {
    let mut settings = Settings::default();
    settings.contact.default_thickness_m = Some(1e-3);
    let mut sim = Simulation::new(settings).unwrap();
    let (xa, ta) = wavy_grid(n, size, 0.0, 0.0);
    let (xb, tb) = wavy_grid(n, size, 1.2e-3, 1.0);
    let a = sim.add_prescribed_surface("a", &xa, &ta, 1e-3, 1e4).unwrap();
    let b = sim.add_prescribed_surface("b", &xb, &tb, 1e-3, 1e4).unwrap();
    (sim, a, b, xa.len())
}

/// Candidates that serve again are pruned of the pairs that can neither become active nor bound
/// a step while they cover the state (a long edge's box spans a whole mesh), and the pairs and
/// CCD bounds they give stay those of the full list and of a fresh broad phase.
#[test]
fn pruned_candidates_give_the_same_pairs_and_ccd_bounds() {
    let mut settings = Settings::default();
    settings.contact.default_thickness_m = Some(1e-3);
    let mut sim = Simulation::new(settings).unwrap();
    // A fine grid under two large triangles 1.5 mm above it (d̂ = 2 mm).
    let (xa, ta) = wavy_grid(12, 0.3, 0.0, 0.0);
    let (xb, tb) = wavy_grid(1, 0.3, 1.5e-3, 0.0);
    sim.add_prescribed_surface("fine", &xa, &ta, 1e-3, 1e4).unwrap();
    sim.add_prescribed_surface("coarse", &xb, &tb, 1e-3, 1e4).unwrap();
    let x = sim.nodes.x.clone();
    // A sweep into `x` from a state with the large triangles 0.6 mm higher.
    let from: Vec<Vector3<f64>> = x
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if i >= xa.len() {
                p + Vector3::new(0.0, 0.0, 6e-4)
            } else {
                *p
            }
        })
        .collect();
    let mid: Vec<Vector3<f64>> = from.iter().zip(&x).map(|(a, b)| 0.5 * (a + b)).collect();
    let key = |pairs: &[super::ContactPair]| pairs.iter().map(|p| (p.kind, p.nodes)).collect::<Vec<_>>();
    at_rest(&mut sim, |contact, _| {
        let fresh: Vec<_> = [&x, &mid, &from]
            .iter()
            .map(|state| {
                contact.candidate_cache = None;
                key(&contact.detect(state))
            })
            .collect();
        assert!(fresh[0].len() > 100, "{} pairs", fresh[0].len());
        let full = contact.candidates_for(None, &from, &x);
        let (full_pt, full_ee) = (full.point_triangle.len(), full.edge_edge.len());
        // The list serves three times (its second reuse prunes it).
        contact.candidate_cache = Some(full);
        for (state, fresh) in [&x, &mid, &from].iter().zip(&fresh) {
            assert_eq!(&key(&contact.detect(state)), fresh);
        }
        let pruned = contact.candidate_cache.take().unwrap();
        let (pt, ee) = (pruned.point_triangle.len(), pruned.edge_edge.len());
        assert!(
            pt + ee < (full_pt + full_ee) / 2,
            "point–triangle {full_pt} → {pt}, edge–edge {full_ee} → {ee}"
        );
        contact.candidate_cache = Some(pruned);
        for (state, fresh) in [&x, &mid, &from].iter().zip(&fresh) {
            assert_eq!(&key(&contact.detect(state)), fresh);
        }
        // A step that drives the large triangles 2 mm down through the grid: CCD bounds it, by
        // the same fraction from the pruned list.
        let through: Vec<Vector3<f64>> = x
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if i >= xa.len() {
                    p - Vector3::new(0.0, 0.0, 2e-3)
                } else {
                    *p
                }
            })
            .collect();
        let full = contact.candidates_for(None, &x, &through);
        let (alpha, queries) = contact.ccd_fraction(&full, &x, &through);
        assert!(alpha < 0.75, "{alpha}");
        let mut pruned = full;
        for _ in 0..2 {
            pruned = contact.candidates_for(Some(pruned), &x, &through);
        }
        let (pruned_alpha, pruned_queries) = contact.ccd_fraction(&pruned, &x, &through);
        assert_eq!(pruned_alpha, alpha);
        assert!(pruned_queries <= queries);
    });
}

/// The pairs found at a state come in one order whichever broad phase found the candidates (a
/// new one, or one cached from a sweep that covers the state): a resumed run, whose first broad
/// phase is new, sums its pairs in the order of the run that kept its cache. And candidates
/// cached across steps are dropped when a thickness changes.
#[test]
fn pairs_come_in_one_order_from_any_covering_candidates() {
    let (mut sim, ..) = stacked_wavy_grids(12, 0.3);
    let x = sim.nodes.x.clone();
    let key = |pairs: &[super::ContactPair]| pairs.iter().map(|p| (p.kind, p.nodes)).collect::<Vec<_>>();

    let fresh = at_rest(&mut sim, |contact, _| {
        contact.candidate_cache = None;
        contact.detect(&x)
    });
    let point_triangle = fresh
        .iter()
        .filter(|p| p.kind == super::pairs::PairKind::PointTriangle)
        .count();
    let edge_edge = fresh
        .iter()
        .filter(|p| p.kind == super::pairs::PairKind::EdgeEdge)
        .count();
    assert!(
        point_triangle > 100 && edge_edge > 100,
        "{point_triangle} point–triangle, {edge_edge} edge–edge pairs"
    );
    // Candidates of a sweep from a shifted, rotated state into `x`: other boxes, another BVH.
    let mut from = x.clone();
    for (i, p) in from.iter_mut().enumerate() {
        *p =
            Vector3::new(0.3 - p.x, 0.3 - p.y, p.z) + Vector3::new(3e-3 * (i as f64).sin(), 0.0, 1e-3 * (i % 3) as f64);
    }
    let swept = at_rest(&mut sim, |contact, _| {
        contact.candidate_cache = None;
        let c = contact.candidates_for(None, &from, &x);
        contact.candidate_cache = Some(c);
        contact.detect(&x)
    });
    assert_eq!(key(&swept), key(&fresh));

    // A thicker object: the next step's detection finds the pairs of its larger d̂ (the
    // candidates cached at the smaller one would miss them).
    let mut sim = Simulation::new(sim.settings.clone()).unwrap();
    let (xa, ta) = wavy_grid(12, 0.3, 0.0, 0.0);
    sim.add_prescribed_surface("a", &xa, &ta, 1e-3, 1e4).unwrap();
    let (xb, tb) = wavy_grid(12, 0.3, 4.5e-3, 1.0);
    let b = sim.add_prescribed_surface("b", &xb, &tb, 1e-3, 1e4).unwrap();
    let x = sim.nodes.x.clone();
    let before = at_rest(&mut sim, |contact, state| {
        contact.before_step(state);
        contact.detect(&x).len()
    });
    sim.contact.set_thickness(b.contact, 4e-3).unwrap();
    let after = at_rest(&mut sim, |contact, state| {
        contact.before_step(state);
        contact.detect(&x).len()
    });
    let new = at_rest(&mut sim, |contact, _| {
        contact.candidate_cache = None;
        contact.detect(&x).len()
    });
    assert_eq!(before, 0);
    assert!(after > 100, "{after} pairs at the larger thickness");
    assert_eq!(after, new);
}

#[test]
fn a_tightened_definite_form_is_the_projected_one_until_the_next_step() {
    use crate::energy::EvalMode;
    // A corner 0.4 mm above the middle of a large triangle: a point–triangle pair far closer than
    // the triangle's size, where `adaptive` takes the Gauss–Newton form.
    let lower = [
        Vector3::new(-1.0, -1.0, 0.0),
        Vector3::new(1.0, -1.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
    ];
    let upper = [
        Vector3::new(0.05, 0.0, 4e-4),
        Vector3::new(0.5, 0.1, 0.6),
        Vector3::new(-0.3, 0.4, 0.7),
    ];
    let mut sim = two_prescribed_triangles(lower, upper);
    at_rest(&mut sim, |contact, state| {
        contact.before_step(state);
        contact.prepare_evaluation(state);
        assert_eq!(contact.pairs().len(), 1, "one point–triangle pair");
        let hessian = |contact: &mut super::Contact| {
            let mut out = vec![0.0; crate::energy::term::element_stride(4)];
            contact.evaluate_element(0, state, EvalMode::ExactHessian, &mut out);
            out
        };
        contact.use_definite_hessian(true);
        let adaptive = hessian(contact);
        assert!(contact.tighten_definite_form(), "the pair's form changes");
        assert!(!contact.tighten_definite_form(), "once");
        let tightened = hessian(contact);
        // The projected form keeps the positive part of the distance's curvature term that the
        // Gauss–Newton form drops: the matrices differ beyond rounding.
        let diff = adaptive
            .iter()
            .zip(&tightened)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let scale = adaptive.iter().map(|a| a.abs()).fold(0.0, f64::max);
        assert!(
            diff > 1e-9 * scale,
            "tightened form equals the adaptive one: {diff:e} of {scale:e}"
        );
        // The gradient is the same: only the Hessian's form changes.
        assert_eq!(adaptive[..13], tightened[..13]);
        // The next time step starts from the configured form.
        contact.before_step(state);
        contact.prepare_evaluation(state);
        assert_eq!(hessian(contact), adaptive);
    });
}

/// A barrier pair and the friction element on its nodes are one element (one scatter into the
/// matrix); friction elements whose pair is gone are elements of their own. Every friction
/// element enters once, and the elements sum to the barrier pairs' and the friction
/// elements' derivatives taken apart.
#[test]
fn friction_elements_are_assembled_once_with_their_pair_or_alone() {
    use crate::energy::kinematics::write_deformable_element;
    use crate::energy::term::element_stride;
    use crate::energy::{EvalMode, HyperDual, Scalar};
    use std::collections::HashMap;
    let (mut sim, a, b, lower_nodes) = stacked_wavy_grids(8, 0.2);
    sim.contact.set_friction(a.contact, b.contact, 0.5).unwrap();
    let masses_kg = vec![1e-3; sim.nodes.len()];
    sim.contact.initialize_stiffness(&masses_kg, 0.01, 9.81);
    // Half the upper grid moved sideways and 0.3 mm closer: pairs there change after the lag,
    // those under the other half stay.
    let moved: Vec<Vector3<f64>> = sim
        .nodes
        .x
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if i >= lower_nodes {
                p + Vector3::new(-1.2e-2, 0.0, -3e-4) * f64::from(p.x < 0.1)
            } else {
                *p
            }
        })
        .collect();
    at_rest(&mut sim, |contact, state| {
        contact.before_step(state);
        let lagged = contact.friction_elements.len();
        contact.prepare_evaluation(state);
        let before: Vec<[u32; 4]> = contact.pairs.iter().map(|p| p.nodes).collect();
        let trial = EvalState { x: &moved, ..*state };
        contact.prepare_evaluation(&trial);
        let same = contact.pairs.iter().filter(|p| before.contains(&p.nodes)).count();
        assert!(
            same > 0 && same < contact.pairs.len(),
            "{same} of {} pairs as lagged",
            contact.pairs.len()
        );
        let carried = contact
            .pair_friction
            .iter()
            .filter(|&&f| f != super::friction_lag::NO_FRICTION)
            .count();
        assert!(
            lagged > 50 && carried > 0 && !contact.lone_friction.is_empty(),
            "{lagged} lagged, {carried} carried, {} alone",
            contact.lone_friction.len()
        );
        let mut entered: Vec<u32> = contact
            .pair_friction
            .iter()
            .copied()
            .filter(|&f| f != super::friction_lag::NO_FRICTION)
            .chain(contact.lone_friction.iter().copied())
            .collect();
        entered.sort_unstable();
        assert_eq!(
            entered,
            (0..lagged as u32).collect::<Vec<_>>(),
            "each friction element once"
        );
        for (p, &f) in contact.pairs.iter().zip(&contact.pair_friction) {
            if f != super::friction_lag::NO_FRICTION {
                assert_eq!(contact.friction_elements[f as usize].nodes, p.nodes);
            }
        }

        // Gradient and Hessian blocks by node, from the elements and from the parts apart.
        type Sums = (HashMap<u32, [f64; 3]>, HashMap<(u32, u32), [f64; 9]>);
        let add = |sums: &mut Sums, nodes: &[u32; 4], out: &[f64]| {
            for (i, &r) in nodes.iter().enumerate().filter(|(_, &r)| r != NO_DOF) {
                let g = sums.0.entry(r).or_default();
                for k in 0..3 {
                    g[k] += out[1 + 3 * i + k];
                }
                for (j, &c) in nodes.iter().enumerate().filter(|(_, &c)| c != NO_DOF) {
                    let h = sums.1.entry((r, c)).or_default();
                    for k in 0..9 {
                        h[k] += out[13 + 9 * (4 * i + j) + k];
                    }
                }
            }
        };
        use crate::energy::term::NO_DOF;
        let mut out = vec![0.0; element_stride(4)];
        let mut merged: Sums = Default::default();
        let n_pairs = contact.pairs.len();
        for e in 0..contact.num_elements() {
            contact.evaluate_element(e, &trial, EvalMode::ExactHessian, &mut out);
            let nodes = if e < n_pairs {
                contact.pairs[e].nodes
            } else {
                contact.friction_elements[contact.lone_friction[e - n_pairs] as usize].nodes
            };
            add(&mut merged, &nodes, &out);
        }
        let mut apart: Sums = Default::default();
        for e in 0..n_pairs {
            contact.evaluate_contact_element(e, &trial, EvalMode::ExactHessian, false, &mut out);
            add(&mut apart, &contact.pairs[e].nodes, &out);
        }
        for f in &contact.friction_elements {
            let mut d = HyperDual::<4>::constant(0.0);
            f.derivatives(&super::Contact::stencil_x(&f.nodes, &moved), &mut d);
            write_deformable_element(&d, trial.dt, &mut out);
            add(&mut apart, &f.nodes, &out);
        }
        let scale = apart.1.values().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0);
        assert_eq!(merged.0.len(), apart.0.len());
        assert_eq!(merged.1.len(), apart.1.len());
        for (key, h) in &apart.1 {
            let m = merged.1[key];
            for k in 0..9 {
                assert!(
                    (m[k] - h[k]).abs() <= 1e-12 * scale,
                    "block {key:?}: {} vs {}",
                    m[k],
                    h[k]
                );
            }
        }
        let gscale = apart.0.values().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (node, g) in &apart.0 {
            for k in 0..3 {
                assert!((merged.0[node][k] - g[k]).abs() <= 1e-12 * gscale);
            }
        }
    });
}
