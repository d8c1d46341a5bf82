//! Contact primitive pairs and their barrier energy.
//!
//! A candidate point–triangle or edge–edge pair is classified by the region of its closest points
//! (IPC, Li et al. 2020; `geometry::distance`) and stored as the lowest-dimensional pair that
//! describes it: point–point, point–edge, point–triangle (plane) or edge–edge (lines). Nearly
//! parallel edge–edge pairs keep all four nodes and are multiplied by the IPC mollifier
//! `m(c) = (2 − c/ε)(c/ε)` of `c = ‖e_a × e_b‖²` (`ε = 10⁻³‖ē_a‖²‖ē_b‖²` at rest), which vanishes
//! as the edges become parallel and keeps the energy smooth there.
//!
//! The energy of a pair is `κ·m·b(d)` with `d = √s` and `s` the squared distance of the pair's
//! region type. Derivatives: generated kernels give `s`, `∇s`, `∇²s` (and those of `c`); the
//! barrier and mollifier are chained on in closed form; the generic function [`pair_energy`] is
//! the hyper-dual oracle the tests compare against.

use super::barrier::{barrier, barrier_generic, BarrierKind};
use crate::energy::psd::project_psd_translation_invariant;
use crate::energy::symbolic::KernelSpec;
use crate::energy::{points_from_flat, HyperDual, Scalar, Vec3};
use crate::generated;
use crate::geometry::distance::EdgeEdgeDistanceType as Ee;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The stored kind of a contact pair, which fixes its nodes and distance formula.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PairKind {
    /// Nodes `[a, b]`: `‖a − b‖²`.
    PointPoint,
    /// Nodes `[p, e0, e1]`: squared distance of `p` to the line of the edge.
    PointEdge,
    /// Nodes `[p, t0, t1, t2]`: squared distance of `p` to the triangle's plane.
    PointTriangle,
    /// Nodes `[ea0, ea1, eb0, eb1]`: squared distance between the two lines.
    EdgeEdge,
    /// Nodes `[ea0, ea1, eb0, eb1]` of nearly parallel edges, with the region of their closest
    /// points; mollified.
    EdgeEdgeMollified(Ee),
}

/// The basic distance formulas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distance {
    /// Point–point.
    PointPoint,
    /// Point–line: nodes `[p, e0, e1]`.
    PointLine,
    /// Point–plane: nodes `[p, t0, t1, t2]`.
    PointPlane,
    /// Line–line: nodes `[ea0, ea1, eb0, eb1]`.
    LineLine,
}

#[allow(clippy::len_without_is_empty)] // a stencil is never empty
impl Distance {
    /// Number of nodes.
    pub fn len(self) -> usize {
        match self {
            Distance::PointPoint => 2,
            Distance::PointLine => 3,
            Distance::PointPlane | Distance::LineLine => 4,
        }
    }
}

#[allow(clippy::len_without_is_empty)] // a stencil is never empty
impl PairKind {
    /// Number of nodes in the stencil.
    pub fn len(self) -> usize {
        match self {
            PairKind::PointPoint => 2,
            PairKind::PointEdge => 3,
            _ => 4,
        }
    }

    /// The distance formula and which stencil nodes it uses, in its order.
    pub fn distance(self) -> (Distance, [usize; 4]) {
        use Ee as R;
        match self {
            PairKind::PointPoint => (Distance::PointPoint, [0, 1, 0, 0]),
            PairKind::PointEdge => (Distance::PointLine, [0, 1, 2, 0]),
            PairKind::PointTriangle => (Distance::PointPlane, [0, 1, 2, 3]),
            PairKind::EdgeEdge => (Distance::LineLine, [0, 1, 2, 3]),
            PairKind::EdgeEdgeMollified(r) => match r {
                R::Ea0Eb0 => (Distance::PointPoint, [0, 2, 0, 0]),
                R::Ea0Eb1 => (Distance::PointPoint, [0, 3, 0, 0]),
                R::Ea1Eb0 => (Distance::PointPoint, [1, 2, 0, 0]),
                R::Ea1Eb1 => (Distance::PointPoint, [1, 3, 0, 0]),
                R::EaEb0 => (Distance::PointLine, [2, 0, 1, 0]),
                R::EaEb1 => (Distance::PointLine, [3, 0, 1, 0]),
                R::Ea0Eb => (Distance::PointLine, [0, 2, 3, 0]),
                R::Ea1Eb => (Distance::PointLine, [1, 2, 3, 0]),
                R::EaEb => (Distance::LineLine, [0, 1, 2, 3]),
            },
        }
    }
}

/// Squared distance of the formula `kind` on points `x` (in the formula's node order).
pub fn distance_sq<S: Scalar>(kind: Distance, x: &[Vec3<S>]) -> S {
    match kind {
        Distance::PointPoint => (x[0] - x[1]).norm_sq(),
        Distance::PointLine => {
            let c = (x[1] - x[0]).cross(&(x[2] - x[0]));
            c.norm_sq() / (x[2] - x[1]).norm_sq()
        }
        Distance::PointPlane => {
            let n = (x[2] - x[1]).cross(&(x[3] - x[1]));
            (x[0] - x[1]).dot(&n).sq() / n.norm_sq()
        }
        Distance::LineLine => {
            let n = (x[1] - x[0]).cross(&(x[3] - x[2]));
            (x[0] - x[2]).dot(&n).sq() / n.norm_sq()
        }
    }
}

/// `‖(ea1 − ea0) × (eb1 − eb0)‖²`, the argument of the edge–edge mollifier.
pub fn edge_cross_sq<S: Scalar>(x: &[Vec3<S>]) -> S {
    (x[1] - x[0]).cross(&(x[3] - x[2])).norm_sq()
}

/// The mollifier `m(c)` with its first and second derivatives.
pub fn mollifier(c: f64, eps: f64) -> (f64, f64, f64) {
    if c >= eps {
        (1.0, 0.0, 0.0)
    } else {
        let r = c / eps;
        ((2.0 - r) * r, 2.0 / eps * (1.0 - r), -2.0 / (eps * eps))
    }
}

/// Generated kernels of the squared distances and of the mollifier argument.
pub fn kernels() -> [KernelSpec; 5] {
    [
        KernelSpec {
            name: "distance_point_point",
            n_inputs: 6,
            n_params: 0,
            energy: |x, _| distance_sq(Distance::PointPoint, &points_from_flat::<_, 2>(x)),
        },
        KernelSpec {
            name: "distance_point_line",
            n_inputs: 9,
            n_params: 0,
            energy: |x, _| distance_sq(Distance::PointLine, &points_from_flat::<_, 3>(x)),
        },
        KernelSpec {
            name: "distance_point_plane",
            n_inputs: 12,
            n_params: 0,
            energy: |x, _| distance_sq(Distance::PointPlane, &points_from_flat::<_, 4>(x)),
        },
        KernelSpec {
            name: "distance_line_line",
            n_inputs: 12,
            n_params: 0,
            energy: |x, _| distance_sq(Distance::LineLine, &points_from_flat::<_, 4>(x)),
        },
        KernelSpec {
            name: "edge_cross",
            n_inputs: 12,
            n_params: 0,
            energy: |x, _| edge_cross_sq(&points_from_flat::<_, 4>(x)),
        },
    ]
}

/// One active contact pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPair {
    /// Kind (fixes the meaning of the nodes).
    pub kind: PairKind,
    /// Global node indices; the first `kind.len()` are used.
    pub nodes: [u32; 4],
    /// Activation distance `d̂ = thickness_a + thickness_b`, m.
    pub dhat: f64,
    /// Mollifier threshold `ε` (m⁴), for mollified edge–edge pairs.
    pub eps_x: f64,
    /// Friction coefficient of the pair's objects.
    pub mu: f64,
    /// Barrier stiffness `κ` of the pair's objects, N/m.
    pub kappa: f64,
    /// The contact objects of the pair's two sides.
    pub objects: [u16; 2],
    /// How many candidates (point–triangle or edge–edge) reduced to this same pair. Duplicates
    /// are merged by summing, never dropped: the energy stays the sum over candidates, which is
    /// continuous when a closest point crosses from a triangle onto its edge (dropping them would
    /// make the energy jump there and stall the line search).
    pub multiplicity: f64,
}

/// Energy of a pair, written generically (the oracle): `κ·m(c)·b(√s)`.
pub fn pair_energy<S: Scalar>(pair: &ContactPair, x: &[Vec3<S>; 4], kappa: f64, kind: BarrierKind) -> S {
    let (dist, idx) = pair.kind.distance();
    let sub: [Vec3<S>; 4] = idx.map(|i| x[i]);
    let d = distance_sq(dist, &sub[..dist.len()]).sqrt();
    let e = barrier_generic(kind, d, pair.dhat) * kappa;
    if let PairKind::EdgeEdgeMollified(_) = pair.kind {
        let r = edge_cross_sq(&x[..]) * (1.0 / pair.eps_x);
        e * S::select_gt(r, S::constant(1.0), || S::constant(1.0), || (-r + 2.0) * r)
    } else {
        e
    }
}

fn distance_kernel(kind: Distance) -> crate::energy::Kernel {
    match kind {
        Distance::PointPoint => generated::distance_point_point,
        Distance::PointLine => generated::distance_point_line,
        Distance::PointPlane => generated::distance_point_plane,
        Distance::LineLine => generated::distance_line_line,
    }
}

/// Which Hessian of a pair's barrier energy to assemble.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, strum::VariantNames)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum PairHessian {
    /// The exact Hessian (indefinite near contact; for tests).
    Exact,
    /// The exact Hessian projected to positive semi-definite by an eigendecomposition (IPC).
    Projected,
    /// Gauss–Newton in the distance: `κ b''(d) ∇d ∇dᵀ`, positive semi-definite by construction
    /// (`b'' > 0`). It drops `κ b'(d) ∇²d`, the part from the curvature of the distance, whose
    /// negative directions projection would remove anyway; about 10× cheaper than projecting.
    GaussNewton,
    /// Gauss–Newton where the distance's curvature term `C = κ b'(d) ∇²d` is below a tenth of
    /// the normal stiffness `κ b''(d) |∇d|²` in norm (a point over the inside of a triangle, or
    /// crossing edges, much closer than their size), projected elsewhere (near corners and edge
    /// ends, where the distance curves like the distance to a point). Where it takes Gauss–Newton
    /// it differs from the projected Hessian by at most `‖C‖`: projecting `GN + C` onto the PSD
    /// cone moves it by no more than `C` moved `GN`, which was already PSD. Costs like
    /// Gauss–Newton on resting cloth, converges like projection (the default).
    Adaptive,
}

/// [`PairHessian::Adaptive`]: the largest curvature term, relative to the normal stiffness, for
/// which a pair takes the Gauss–Newton form.
pub const ADAPTIVE_CURVATURE_RATIO: f64 = 0.1;

/// Value, gradient and Hessian of a pair's energy with respect to its four node positions
/// (unused nodes get zeros). Returns the distance `d`, m.
pub fn pair_derivatives(
    pair: &ContactPair,
    x: &[Vector3<f64>; 4],
    kappa: f64,
    kind: BarrierKind,
    hessian: PairHessian,
    out: &mut HyperDual<4>,
) -> f64 {
    let (dist, idx) = pair.kind.distance();
    let m = dist.len();
    let mut flat = [0.0; 12];
    for (k, &i) in idx[..m].iter().enumerate() {
        flat[3 * k..3 * k + 3].copy_from_slice(x[i].as_slice());
    }
    let mut gs = [0.0; 12];
    let mut hs = [0.0; 144];
    let s = distance_kernel(dist)(&flat[..3 * m], &[], &mut gs[..3 * m], &mut hs[..9 * m * m]);
    let d = s.max(0.0).sqrt();
    let (b, db, ddb) = barrier(kind, d, pair.dhat);
    // E(s) = κ b(√s): E' = κ b'/(2d), E'' = κ (b'' − b'/d)/(4d²).
    let e = kappa * b;
    let e1 = kappa * db / (2.0 * d);
    let e2 = kappa * (ddb - db / d) / (4.0 * d * d);
    // Energy in the sub-stencil's coordinates.
    let mut g = [0.0; 12];
    let mut h = [0.0; 144];
    let n = 3 * m;
    let mollified = matches!(pair.kind, PairKind::EdgeEdgeMollified(_));
    let gauss_newton = !mollified
        && b != 0.0
        && match hessian {
            PairHessian::GaussNewton => true,
            PairHessian::Adaptive => {
                // ‖κ b' ∇²d‖_F against the normal stiffness κ b'' |∇d|², with ∇d = ∇s/(2d) and
                // ∇²d = (∇²s − ∇s∇sᵀ/(2s))/(2d).
                let mut curvature_sq = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        curvature_sq += (hs[i * n + j] - gs[i] * gs[j] / (2.0 * s)).powi(2);
                    }
                }
                let curvature = (kappa * db / (2.0 * d)).abs() * curvature_sq.sqrt();
                let normal = kappa * ddb * gs[..n].iter().map(|v| v * v).sum::<f64>() / (4.0 * d * d);
                curvature <= ADAPTIVE_CURVATURE_RATIO * normal
            }
            PairHessian::Exact | PairHessian::Projected => false,
        };
    let project = match hessian {
        PairHessian::Projected => true,
        PairHessian::Adaptive => !gauss_newton,
        PairHessian::Exact | PairHessian::GaussNewton => false,
    };
    if b != 0.0 {
        if gauss_newton {
            // ∇d = ∇s/(2d): κ b'' ∇d∇dᵀ = κ b''/(4d²) ∇s∇sᵀ.
            let c = kappa * ddb / (4.0 * d * d);
            for i in 0..n {
                g[i] = e1 * gs[i];
                for j in 0..n {
                    h[i * n + j] = c * gs[i] * gs[j];
                }
            }
        } else {
            for i in 0..n {
                g[i] = e1 * gs[i];
                for j in 0..n {
                    h[i * n + j] = e2 * gs[i] * gs[j] + e1 * hs[i * n + j];
                }
            }
        }
    }
    // Embed into the four-node stencil.
    out.value = e;
    let og = out.grad.as_flattened_mut();
    og.iter_mut().for_each(|v| *v = 0.0);
    let oh = out.hess.as_flattened_mut().as_flattened_mut().as_flattened_mut();
    oh.iter_mut().for_each(|v| *v = 0.0);
    let full = |k: usize| 3 * idx[k / 3] + k % 3;
    if let PairKind::EdgeEdgeMollified(_) = pair.kind {
        let mut gb = [0.0; 12];
        let mut hb = [0.0; 144];
        // The adaptive mode builds its own Hessian (below): only the others need the barrier's.
        let exact_needed = hessian != PairHessian::Adaptive;
        for i in 0..n {
            gb[full(i)] = g[i];
            for j in 0..n {
                if exact_needed {
                    hb[full(i) * 12 + full(j)] = h[i * n + j];
                }
            }
        }
        let mut flat4 = [0.0; 12];
        for k in 0..4 {
            flat4[3 * k..3 * k + 3].copy_from_slice(x[k].as_slice());
        }
        let mut gc = [0.0; 12];
        let mut hc = [0.0; 144];
        let c = generated::edge_cross(&flat4, &[], &mut gc, &mut hc);
        let (mo, m1, m2) = mollifier(c, pair.eps_x);
        // (m b)'' = m b'' + b m'' + ∇b ∇mᵀ + ∇m ∇bᵀ, with ∇m = m' ∇c, ∇²m = m'' ∇c∇cᵀ + m' ∇²c.
        out.value = mo * e;
        for i in 0..12 {
            og[i] = mo * gb[i] + e * m1 * gc[i];
        }
        if exact_needed {
            for i in 0..12 {
                let gm_i = m1 * gc[i];
                for j in 0..12 {
                    let gm_j = m1 * gc[j];
                    let hm = m2 * gc[i] * gc[j] + m1 * hc[i * 12 + j];
                    oh[i * 12 + j] = mo * hb[i * 12 + j] + e * hm + gb[i] * gm_j + gm_i * gb[j];
                }
            }
        }
        if hessian == PairHessian::Adaptive {
            // The mollifier's curvature makes these Hessians far from their Gauss–Newton form
            // (its terms are as large as the normal stiffness), yet with it Newton takes the same
            // iterations on stacked cloth layers (a third of the pairs there: parallel grid edges)
            // and no eigen-decomposition.
            mollified_gauss_newton(&flat4, &gs[..n], &full, kappa * ddb / (4.0 * d * d), mo, e, m1, oh);
        } else if hessian != PairHessian::Exact {
            // Distances and the mollifier's edge cross product are translation invariant.
            project_psd_translation_invariant(oh, 4);
        }
    } else {
        if project {
            project_psd_translation_invariant(&mut h[..n * n], m);
        }
        for i in 0..n {
            og[full(i)] = g[i];
            for j in 0..n {
                oh[full(i) * 12 + full(j)] = h[i * n + j];
            }
        }
    }
    d
}

/// The Gauss–Newton Hessian of a mollified edge–edge pair `E = m(c)·e(d)`:
/// `m κ b'' ∇d∇dᵀ + e m' 2JᵀJ`, with `J = ∂w/∂x` of the cross product `w = ea × eb` (`c = |w|²`).
/// Both parts are positive semi-definite (m, e, m', b'' ≥ 0); it leaves out the barrier's and the
/// cross product's curvature, the mollifier's (negative) second derivative and the two cross
/// terms, as the pair's Gauss–Newton form does for unmollified pairs.
#[allow(clippy::too_many_arguments)]
fn mollified_gauss_newton(
    x: &[f64; 12],
    gs: &[f64],
    full: &dyn Fn(usize) -> usize,
    normal: f64,
    mo: f64,
    e: f64,
    m1: f64,
    oh: &mut [f64],
) {
    oh.iter_mut().for_each(|v| *v = 0.0);
    let n = gs.len();
    let c = normal * mo;
    for i in 0..n {
        for j in 0..n {
            oh[full(i) * 12 + full(j)] += c * gs[i] * gs[j];
        }
    }
    let ea = Vector3::new(x[3] - x[0], x[4] - x[1], x[5] - x[2]);
    let eb = Vector3::new(x[9] - x[6], x[10] - x[7], x[11] - x[8]);
    let (sa, sb) = (ea.cross_matrix(), eb.cross_matrix());
    // ∂w/∂x = [ [eb]×, −[eb]×, −[ea]×, [ea]× ].
    let blocks = [sb, -sb, -sa, sa];
    let w = 2.0 * e * m1;
    for a in 0..4 {
        for b in 0..4 {
            let jtj = blocks[a].transpose() * blocks[b];
            for i in 0..3 {
                for j in 0..3 {
                    oh[(3 * a + i) * 12 + 3 * b + j] += w * jtj[(i, j)];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::potential::symmetrize;
    use rand::{Rng, SeedableRng};

    fn check(pair: &ContactPair, x: &[Vector3<f64>; 4], kind: BarrierKind) {
        let kappa = 3.7;
        let mut fast = HyperDual::<4>::constant(0.0);
        pair_derivatives(pair, x, kappa, kind, PairHessian::Exact, &mut fast);
        let mut oracle = pair_energy(pair, &HyperDual::<4>::variables(x), kappa, kind);
        symmetrize(&mut oracle);
        let scale = oracle
            .hess
            .as_flattened()
            .as_flattened()
            .as_flattened()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-300);
        assert!(
            (fast.value - oracle.value).abs() <= 1e-10 * oracle.value.abs().max(1e-300),
            "{pair:?}"
        );
        let gs = oracle
            .gradient_flat()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-300);
        for (a, b) in fast.gradient_flat().iter().zip(oracle.gradient_flat()) {
            assert!((a - b).abs() <= 1e-8 * gs, "{pair:?}: gradient {a} vs {b}");
        }
        let fh = fast.hess.as_flattened().as_flattened().as_flattened();
        let oh = oracle.hess.as_flattened().as_flattened().as_flattened();
        for (a, b) in fh.iter().zip(oh) {
            assert!((a - b).abs() <= 1e-7 * scale, "{pair:?}: Hessian {a} vs {b}");
        }
        // Finite differences of the oracle's energy confirm the oracle itself.
        let h = 1e-8;
        for k in 0..12 {
            let mut xp = *x;
            let mut xm = *x;
            xp[k / 3][k % 3] += h;
            xm[k / 3][k % 3] -= h;
            let f = |y: &[Vector3<f64>; 4]| pair_energy(pair, &y.map(|p| Vec3::<f64>::constant(&p)), kappa, kind);
            let fd = (f(&xp) - f(&xm)) / (2.0 * h);
            assert!(
                (fd - oracle.gradient_flat()[k]).abs() <= 1e-5 * gs,
                "{pair:?}: FD {fd} vs {}",
                oracle.gradient_flat()[k]
            );
        }
    }

    /// A pair on nodes 0–3 with d̂ = 0.5 m and ε_x = 1e-2 (points within ±0.2 m are in range).
    fn unit_pair(kind: PairKind) -> ContactPair {
        ContactPair {
            kind,
            nodes: [0, 1, 2, 3],
            dhat: 0.5,
            eps_x: 1e-2,
            mu: 0.0,
            kappa: 1.0,
            objects: [0, 0],
            multiplicity: 1.0,
        }
    }

    #[test]
    fn derivatives_of_every_pair_kind_match_the_oracle() {
        use Ee as R;
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let kinds = [
            PairKind::PointPoint,
            PairKind::PointEdge,
            PairKind::PointTriangle,
            PairKind::EdgeEdge,
            PairKind::EdgeEdgeMollified(R::EaEb),
            PairKind::EdgeEdgeMollified(R::Ea0Eb1),
            PairKind::EdgeEdgeMollified(R::EaEb1),
        ];
        for kind in kinds {
            for barrier_kind in [BarrierKind::Log, BarrierKind::Cubic] {
                for _ in 0..5 {
                    // Four points within a small ball: distances below d̂ = 0.5.
                    let x: [Vector3<f64>; 4] = std::array::from_fn(|_| {
                        Vector3::new(
                            rng.random_range(-0.2..0.2),
                            rng.random_range(-0.2..0.2),
                            rng.random_range(-0.2..0.2),
                        )
                    });
                    let mut x = x;
                    if let PairKind::EdgeEdgeMollified(_) = kind {
                        // Nearly parallel edges: the mollifier is active.
                        x[3] = x[2] + (x[1] - x[0]) * 0.9 + Vector3::new(0.01, -0.004, 0.002);
                    }
                    let pair = unit_pair(kind);
                    check(&pair, &x, barrier_kind);
                }
            }
        }
    }

    /// In the adaptive mode a mollified edge–edge pair `m(c)·κb(d)` takes its Gauss–Newton form
    /// `m κ b'' ∇d∇dᵀ + κb m' 2JᵀJ` (`J = ∂(ea × eb)/∂x`, by central differences here): positive
    /// semi-definite, with the exact gradient.
    #[test]
    fn mollified_pairs_take_their_gauss_newton_form() {
        use crate::energy::psd::is_positive_semidefinite;
        use Ee as R;
        let x = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.3, 0.02, 0.0),
            Vector3::new(0.05, -0.01, 0.12),
            Vector3::new(0.32, 0.015, 0.121),
        ];
        for region in [R::EaEb, R::EaEb1, R::Ea0Eb1] {
            let pair = unit_pair(PairKind::EdgeEdgeMollified(region));
            let kappa = 2.5;
            let mut adaptive = HyperDual::<4>::constant(0.0);
            let mut exact = HyperDual::<4>::constant(0.0);
            pair_derivatives(&pair, &x, kappa, BarrierKind::Log, PairHessian::Adaptive, &mut adaptive);
            pair_derivatives(&pair, &x, kappa, BarrierKind::Log, PairHessian::Exact, &mut exact);
            assert_eq!(adaptive.value, exact.value);
            assert_eq!(adaptive.gradient_flat(), exact.gradient_flat());
            let h = adaptive.hess.as_flattened().as_flattened().as_flattened().to_vec();
            assert!(is_positive_semidefinite(&h, 12), "{region:?}");

            // The oracle, by central differences of d and of w = ea × eb.
            let flat: Vec<f64> = x.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
            let at = |f: &[f64]| -> [Vector3<f64>; 4] {
                std::array::from_fn(|k| Vector3::new(f[3 * k], f[3 * k + 1], f[3 * k + 2]))
            };
            let (dist, idx) = pair.kind.distance();
            let m_used = match dist {
                Distance::PointPoint => 2,
                Distance::PointLine => 3,
                _ => 4,
            };
            let d_of = |p: &[Vector3<f64>; 4]| {
                let sub: Vec<Vec3<f64>> = idx[..m_used]
                    .iter()
                    .map(|&i| Vec3::new(p[i].x, p[i].y, p[i].z))
                    .collect();
                distance_sq(dist, &sub).sqrt()
            };
            let w_of = |p: &[Vector3<f64>; 4]| (p[1] - p[0]).cross(&(p[3] - p[2]));
            let step = 1e-6;
            let mut grad_d = [0.0; 12];
            let mut jac_w = [Vector3::zeros(); 12];
            for k in 0..12 {
                let (mut plus, mut minus) = (flat.clone(), flat.clone());
                plus[k] += step;
                minus[k] -= step;
                grad_d[k] = (d_of(&at(&plus)) - d_of(&at(&minus))) / (2.0 * step);
                jac_w[k] = (w_of(&at(&plus)) - w_of(&at(&minus))) / (2.0 * step);
            }
            let d = d_of(&x);
            let (b, _, ddb) = barrier(BarrierKind::Log, d, pair.dhat);
            let (mo, m1, _) = mollifier(w_of(&x).norm_squared(), pair.eps_x);
            assert!(mo < 1.0 && m1 > 0.0, "the mollifier is active");
            let scale = h.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..12 {
                for j in 0..12 {
                    let oracle =
                        mo * kappa * ddb * grad_d[i] * grad_d[j] + kappa * b * m1 * 2.0 * jac_w[i].dot(&jac_w[j]);
                    assert!(
                        (h[12 * i + j] - oracle).abs() <= 1e-6 * scale,
                        "{region:?} ({i}, {j}): {} vs {oracle}",
                        h[12 * i + j]
                    );
                }
            }
        }
    }

    /// The adaptive Hessian is positive semi-definite, equals the projected one where the
    /// distance curves strongly (point–point) and is within the stated bound of it where it takes
    /// Gauss–Newton (a point just above a large triangle, crossing edges far apart from their
    /// ends: both common in resting cloth).
    #[test]
    fn adaptive_hessian_is_psd_and_near_the_projected_one() {
        use crate::energy::psd::is_positive_semidefinite;
        let flat = |h: &HyperDual<4>| h.hess.as_flattened().as_flattened().as_flattened().to_vec();
        let pair = |kind| ContactPair {
            kind,
            nodes: [0, 1, 2, 3],
            dhat: 1e-3,
            eps_x: 1e-12,
            mu: 0.0,
            kappa: 1.0,
            objects: [0, 0],
            multiplicity: 1.0,
        };
        let cases = [
            // A point 0.3 mm above the inside of a 1 cm triangle.
            (
                PairKind::PointTriangle,
                [
                    [0.002, 0.003, 3e-4],
                    [0.0, 0.0, 0.0],
                    [0.01, 0.0, 0.0],
                    [0.0, 0.01, 0.0],
                ],
                true,
            ),
            // Two crossing 1 cm edges 0.4 mm apart.
            (
                PairKind::EdgeEdge,
                [
                    [-0.005, 0.0, 4e-4],
                    [0.005, 0.001, 4e-4],
                    [0.0, -0.005, 0.0],
                    [0.001, 0.005, 0.0],
                ],
                true,
            ),
            // Two points: the distance curves like 1/d, always projected.
            (
                PairKind::PointPoint,
                [[0.0, 0.0, 3e-4], [1e-4, 0.0, 0.0], [0.0; 3], [0.0; 3]],
                false,
            ),
        ];
        for (kind, points, expect_gauss_newton) in cases {
            let x = points.map(Vector3::from);
            let p = pair(kind);
            let mut adaptive = HyperDual::<4>::constant(0.0);
            let mut projected = HyperDual::<4>::constant(0.0);
            let mut gauss_newton = HyperDual::<4>::constant(0.0);
            pair_derivatives(&p, &x, 1e4, BarrierKind::Log, PairHessian::Adaptive, &mut adaptive);
            pair_derivatives(&p, &x, 1e4, BarrierKind::Log, PairHessian::Projected, &mut projected);
            pair_derivatives(
                &p,
                &x,
                1e4,
                BarrierKind::Log,
                PairHessian::GaussNewton,
                &mut gauss_newton,
            );
            let (a, pr, gn) = (flat(&adaptive), flat(&projected), flat(&gauss_newton));
            assert!(is_positive_semidefinite(&a, 12), "{kind:?}");
            assert_eq!(adaptive.gradient_flat(), projected.gradient_flat());
            if expect_gauss_newton {
                assert_eq!(a, gn, "{kind:?} takes Gauss–Newton");
                // ‖H_adaptive − H_projected‖ ≤ 0.1 × the normal stiffness (the Gauss–Newton
                // matrix's only eigenvalue, its trace).
                let normal: f64 = (0..12).map(|i| gn[13 * i]).sum();
                let diff = a.iter().zip(&pr).map(|(u, v)| (u - v).powi(2)).sum::<f64>().sqrt();
                assert!(
                    diff <= ADAPTIVE_CURVATURE_RATIO * normal,
                    "{kind:?}: {diff} vs {normal}"
                );
            } else {
                assert_eq!(a, pr, "{kind:?} is projected");
            }
        }
    }
}
