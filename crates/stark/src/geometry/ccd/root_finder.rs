//! Inclusion-based interval root finder for linear CCD (after Wang et al. 2021, "A Large Scale
//! Benchmark and an Inclusion-Based Algorithm for Continuous Collision Detection").
//!
//! The unknowns are `(t, u, v) ∈ [0, t_max] × [0, 1]²`. With the vertices moving linearly,
//! `x_i(t) = x_i⁰ + t (x_i¹ − x_i⁰)`, the gap vector is
//!
//! - point–triangle (`u + v ≤ 1`): `F = x_p(t) − [x_t0(t) + u (x_t1(t) − x_t0(t)) + v (x_t2(t) − x_t0(t))]`,
//! - edge–edge: `F = [x_a0(t) + u (x_a1(t) − x_a0(t))] − [x_b0(t) + v (x_b1(t) − x_b0(t))]`,
//!
//! and the primitives are within `δ` at time `t` iff `|F(t, u, v)| ≤ δ` for some `(u, v)`. Each
//! component of `F` is *multilinear* (degree ≤ 1 in each of `t`, `u`, `v`), so over a box `F` is the
//! trilinear interpolation of its 8 corner values: its range lies in their convex hull, and per
//! axis between their minimum and maximum. The corners are evaluated in f64 with the a-priori
//! rounding bound [`ERROR_FACTOR`]. A box is discarded only when this proves `|F| > δ` on all of
//! it ([`assess`]: axis-aligned inclusion, or a separating direction); the others are split
//! ([`directional_time_split`], else bisection by [`choose_split`]). Boxes are processed in order
//! of their lower time bound, so the box at which the search stops (accepted, unsplittable, or
//! reached when the iteration budget runs out) has the smallest lower time bound of all boxes
//! that may still contain a root; that bound is returned, and it is never later than the first
//! root.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// The two CCD stencils. Vertex order: `[p, t0, t1, t2]` and `[ea0, ea1, eb0, eb1]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stencil {
    PointTriangle,
    EdgeEdge,
}

/// Rounding-error bound of one corner evaluation, relative to the largest coordinate magnitude on
/// that axis (`M_k`): `err_k = ERROR_FACTOR · M_k + ERROR_FLOOR`.
///
/// Derivation (standard model `fl(a ∘ b) = (a ∘ b)(1 + δ)`, `|δ| ≤ u = 2⁻⁵³`, `t, u, v ∈ [0, 1]`
/// exact, all input coordinates `≤ M`): `d = fl(x¹ − x⁰)` has error `≤ 2Mu`; `x(t) = fl(x⁰ + fl(t d))`
/// has error `≤ 5Mu` (its exact value is a convex combination, `≤ M`); a difference of two positions
/// `≤ 12Mu`; times `u` or `v`, `≤ 14Mu`; the point on the triangle (`|·| ≤ 3M`) `≤ 37Mu`; the final
/// difference `≤ 46Mu` (point–triangle; edge–edge `≤ 42Mu`). Rounding each *input* coordinate to f64
/// (e.g. from exact rationals) moves `F` by at most `4Mu` more (the absolute weights of the inputs sum
/// to at most 4). Total `≤ 50Mu`; the constant below is `128u`, a 2.5× margin that also covers
/// second-order terms and the rounding of `min − err`/`max + err`.
pub(crate) const ERROR_FACTOR: f64 = 64.0 * f64::EPSILON;

/// Absolute term of the error bound, covering gradual underflow (each operation on subnormal
/// numbers may lose up to `2⁻¹⁰⁷⁵` absolutely). Negligible after the power-of-two rescaling done by
/// the drivers, which brings the largest coordinate into `[1, 2)`.
pub(crate) const ERROR_FLOOR: f64 = f64::MIN_POSITIVE;

/// A CCD query: start positions and displacements of the four vertices, already rescaled.
#[derive(Debug, Clone)]
pub(crate) struct Problem {
    stencil: Stencil,
    x0: [[f64; 3]; 4],
    dx: [[f64; 3]; 4],
    /// Per-axis bound on the error of every computed corner value of `F`.
    err: [f64; 3],
}

impl Problem {
    /// A problem from start and end positions (all finite).
    pub(crate) fn new(stencil: Stencil, x_t0: &[[f64; 3]; 4], x_t1: &[[f64; 3]; 4]) -> Self {
        let mut dx = [[0.0; 3]; 4];
        let mut err = [0.0; 3];

        for k in 0..3 {
            let mut m: f64 = 0.0;
            for i in 0..4 {
                dx[i][k] = x_t1[i][k] - x_t0[i][k];
                m = m.max(x_t0[i][k].abs()).max(x_t1[i][k].abs());
            }
            err[k] = ERROR_FACTOR * m + ERROR_FLOOR;
        }
        Self {
            stencil,
            x0: *x_t0,
            dx,
            err,
        }
    }

    /// The largest per-axis error bound.
    pub(crate) fn max_err(&self) -> f64 {
        self.err[0].max(self.err[1]).max(self.err[2])
    }

    /// `F` at the 8 corners of `b`; corner index `4·it + 2·iu + iv`. The operation order is the
    /// one analysed in [`ERROR_FACTOR`].
    fn corners(&self, b: &Domain) -> [[f64; 3]; 8] {
        let mut f = [[0.0; 3]; 8];
        for (it, &t) in b.t.iter().enumerate() {
            let x: [[f64; 3]; 4] = std::array::from_fn(|i| std::array::from_fn(|k| self.x0[i][k] + t * self.dx[i][k]));
            for k in 0..3 {
                match self.stencil {
                    Stencil::PointTriangle => {
                        let g1 = x[2][k] - x[1][k];
                        let g2 = x[3][k] - x[1][k];
                        for (iu, &u) in b.u.iter().enumerate() {
                            let s1 = x[1][k] + u * g1;
                            for (iv, &v) in b.v.iter().enumerate() {
                                f[4 * it + 2 * iu + iv][k] = x[0][k] - (s1 + v * g2);
                            }
                        }
                    }
                    Stencil::EdgeEdge => {
                        let ga = x[1][k] - x[0][k];
                        let gb = x[3][k] - x[2][k];
                        for (iu, &u) in b.u.iter().enumerate() {
                            let pa = x[0][k] + u * ga;
                            for (iv, &v) in b.v.iter().enumerate() {
                                f[4 * it + 2 * iu + iv][k] = pa - (x[2][k] + v * gb);
                            }
                        }
                    }
                }
            }
        }
        f
    }
}

/// A box of the parameter domain.
#[derive(Debug, Clone, Copy)]
struct Domain {
    t: [f64; 2],
    u: [f64; 2],
    v: [f64; 2],
}

impl Domain {
    fn interval(&self, dim: usize) -> [f64; 2] {
        match dim {
            0 => self.t,
            1 => self.u,
            _ => self.v,
        }
    }

    /// The two halves along `dim`, if the interval can still be split in floating point.
    fn split(&self, dim: usize) -> Option<(Domain, Domain)> {
        let [lo, hi] = self.interval(dim);
        let mid = 0.5 * (lo + hi);
        if !(lo < mid && mid < hi) {
            return None;
        }
        let (mut a, mut b) = (*self, *self);
        match dim {
            0 => (a.t[1], b.t[0]) = (mid, mid),
            1 => (a.u[1], b.u[0]) = (mid, mid),
            _ => (a.v[1], b.v[0]) = (mid, mid),
        }
        Some((a, b))
    }
}

/// Heap entry ordered so that `BinaryHeap` (a max-heap) pops the smallest lower time bound first,
/// and among equal bounds the newest entry. Ties do not affect the answer (any box with the
/// smallest bound gives the same TOI), but newest-first dives towards an acceptable box instead
/// of refining every box on a continuum of contacts (parallel edges, a face landing on a face)
/// breadth-first, which costs ~1/tolerance boxes.
struct Entry {
    domain: Domain,
    seq: u64,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other.domain.t[0]
            .total_cmp(&self.domain.t[0])
            .then(self.seq.cmp(&other.seq))
    }
}

/// Settings of one solve, in the problem's (rescaled) units.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Settings {
    /// Minimum separation `δ ≥ 0`.
    pub delta: f64,
    /// Accept a box when its inclusion is at most this wide on every axis, or when a corner at its
    /// start time is within `δ + tolerance`.
    pub tolerance: f64,
    /// Maximum number of boxes examined.
    pub max_iterations: usize,
    /// End of the time interval, in `[0, 1]`.
    pub tmax: f64,
    /// Never accept a box starting at `t = 0` while it can still be split (used when the
    /// configuration at `t = 0` is known to be separated).
    pub no_zero_toi: bool,
}

/// Result of a solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Outcome {
    /// A time `≤` the first time the primitives may be within `δ`, or `None` if they provably
    /// stay farther apart on `[0, tmax]`.
    pub toi: Option<f64>,
    /// Number of boxes examined.
    pub iterations: usize,
}

/// Whether the corner values `f` (each exact value within `err` of the computed one) prove that
/// `|F| > δ` on the whole box, and the largest width of the axis-aligned inclusion.
///
/// Two rigorous tests, the second only when the first fails:
/// 1. **Axis-aligned inclusion** `[min − err, max + err]` per axis: excluded if that box lies
///    farther than `δ` from the origin (for `δ = 0`: one axis range misses 0).
/// 2. **Separating direction.** A multilinear `F` is, at every point of the box, a convex
///    combination of its 8 corner values (trilinear interpolation is exact for it), so
///    `F(box) ⊆ conv{F_c}`. With `n` the normalised mean of the corners, `n·x ≥ min_c n·F_c − E`
///    on that hull, where `E = Σ_k |n_k| err_k` plus a rounding allowance for the dot products;
///    if that exceeds `δ·|n|`, every point is farther than `δ`. This test is what keeps tangential
///    approaches cheap for `δ > 0`: the axis-aligned box of a curved piece of the `δ`-sphere
///    reaches much closer to the origin than the piece itself.
fn assess(f: &[[f64; 3]; 8], err: &[f64; 3], delta: f64, delta_sq_bound: f64) -> (bool, f64) {
    let mut gap_sq = 0.0;
    let mut separated_axis = false;
    let mut width: f64 = 0.0;
    let mut mean = [0.0f64; 3];
    for k in 0..3 {
        let (mut lo, mut hi) = (f[0][k], f[0][k]);
        for c in &f[1..] {
            lo = lo.min(c[k]);
            hi = hi.max(c[k]);
        }
        mean[k] = 0.5 * (lo + hi);
        lo -= err[k];
        hi += err[k];
        let gap = if lo > 0.0 {
            lo
        } else if hi < 0.0 {
            -hi
        } else {
            0.0
        };
        separated_axis |= gap > 0.0;
        gap_sq += gap * gap;
        width = width.max(hi - lo);
    }
    // For δ = 0 one separating axis suffices (and is immune to underflow of `gap²`).
    let excluded = if delta > 0.0 {
        gap_sq > delta_sq_bound
    } else {
        separated_axis
    };
    if excluded {
        return (true, width);
    }
    let norm = (mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]).sqrt();
    let excluded = norm > 0.0 && excluded_along(f, err, delta, &mean.map(|m| m / norm));
    (excluded, width)
}

/// Lower bound `θ` such that `n·F_c > θ` for every corner `c` proves `|F| > δ` on the box's hull
/// (see [`assess`], test 2): `δ·(1 + 16ε)` plus `Σ_k |n_k| err_k` plus a rounding allowance of
/// `8ε·max_c Σ_k |n_k F_c,k|` for the dot products. `n` must be a rounded unit vector
/// (`|n| ≤ 1 + 4u`).
fn direction_threshold(f: &[[f64; 3]; 8], err: &[f64; 3], delta: f64, n: &[f64; 3]) -> f64 {
    let mut magnitude: f64 = 0.0;
    for c in f {
        magnitude = magnitude.max(n[0].abs() * c[0].abs() + n[1].abs() * c[1].abs() + n[2].abs() * c[2].abs());
    }
    delta * (1.0 + 16.0 * f64::EPSILON)
        + n[0].abs() * err[0]
        + n[1].abs() * err[1]
        + n[2].abs() * err[2]
        + 8.0 * f64::EPSILON * magnitude
}

#[inline]
fn dot(n: &[f64; 3], c: &[f64; 3]) -> f64 {
    n[0] * c[0] + n[1] * c[1] + n[2] * c[2]
}

/// The separating-direction test of [`assess`] for a given direction `n`.
fn excluded_along(f: &[[f64; 3]; 8], err: &[f64; 3], delta: f64, n: &[f64; 3]) -> bool {
    let theta = direction_threshold(f, err, delta, n);
    f.iter().all(|c| dot(n, c) > theta)
}

/// Predicts how far in time the box stays provably separated along the direction `n`, and returns
/// a split time `s` with `[t_lo, s]` expected to be excluded, or `None` when that is less than 5%
/// of the box.
///
/// For fixed `(u, v)`, `F` is linear in `t`, so `n·F` at the corners of a sub-box `[t_lo, s]` is
/// the linear interpolation of the parent's corner values; the first time one of them reaches the
/// threshold bounds `s`, and 90% of it leaves a margin. This is only a prediction: the caller
/// evaluates the lower part exactly before discarding it. It is what keeps tangential approaches
/// with `δ > 0` cheap, where bisection would subdivide the whole penetration disk in `(u, v)`.
fn directional_time_split(b: &Domain, f: &[[f64; 3]; 8], err: &[f64; 3], delta: f64, n: &[f64; 3]) -> Option<f64> {
    let theta = direction_threshold(f, err, delta, n);
    let mut frac = f64::INFINITY;
    for c in 0..4 {
        let (at_lo, at_hi) = (dot(n, &f[c]), dot(n, &f[c | 4]));
        if at_lo <= theta || at_lo.is_nan() {
            return None;
        }
        if at_hi < theta {
            frac = frac.min((at_lo - theta) / (at_lo - at_hi));
        }
    }
    let frac = 0.9 * frac;
    if !(0.05..1.0).contains(&frac) {
        return None;
    }
    let split = b.t[0] + frac * (b.t[1] - b.t[0]);
    (b.t[0] < split && split < b.t[1]).then_some(split)
}

/// The normalised mean of the corner values, if it is non-zero.
fn mean_direction(f: &[[f64; 3]; 8]) -> Option<[f64; 3]> {
    let mut mean = [0.0f64; 3];
    for k in 0..3 {
        let (mut lo, mut hi) = (f[0][k], f[0][k]);
        for c in &f[1..] {
            lo = lo.min(c[k]);
            hi = hi.max(c[k]);
        }
        mean[k] = 0.5 * (lo + hi);
    }
    let norm = (mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]).sqrt();
    (norm > 0.0).then(|| mean.map(|m| m / norm))
}

/// Corner bit of each parameter in the corner index `4·it + 2·iu + iv`.
const DIM_BITS: [usize; 3] = [4, 2, 1];

/// Picks the dimension to bisect and returns the two halves, or `None` if no dimension can be
/// split in floating point.
///
/// Heuristic (it affects only speed): prefer the split for which more halves would be excluded,
/// predicting each half's corner values from the parent's (for a multilinear function, the value
/// at a midpoint is the mean of the two corner values); among equals, prefer the parameter `F`
/// is most sensitive to over this box. Balancing sensitivities alone is efficient for isolated
/// contacts, but for a continuum of contacts at one time (parallel edges or faces meeting) it would
/// subdivide `u, v` along the whole contact before narrowing `t`; the look-ahead splits `t` there,
/// because the earlier half is immediately excluded.
fn choose_split(
    problem: &Problem,
    b: &Domain,
    f: &[[f64; 3]; 8],
    delta: f64,
    delta_sq_bound: f64,
) -> Option<(Domain, Domain)> {
    let mut best: Option<((usize, f64), (Domain, Domain))> = None;
    for (dim, &bit) in DIM_BITS.iter().enumerate() {
        let Some((lo_half, hi_half)) = b.split(dim) else {
            continue;
        };
        let mut sens: f64 = 0.0;
        let mut mid = [[0.0; 3]; 8];
        for c in (0..8).filter(|c| c & bit == 0) {
            for k in 0..3 {
                sens = sens.max((f[c | bit][k] - f[c][k]).abs());
                mid[c][k] = 0.5 * (f[c][k] + f[c | bit][k]);
            }
        }
        let mut lo_vals = *f;
        let mut hi_vals = *f;
        for c in (0..8).filter(|c| c & bit == 0) {
            lo_vals[c | bit] = mid[c];
            hi_vals[c] = mid[c];
        }
        let mut excluded_halves = 0;
        for (half, vals) in [(&lo_half, &lo_vals), (&hi_half, &hi_vals)] {
            let outside = problem.stencil == Stencil::PointTriangle && half.u[0] + half.v[0] > 1.0;
            if outside || assess(vals, &problem.err, delta, delta_sq_bound).0 {
                excluded_halves += 1;
            }
        }
        let better = match &best {
            None => true,
            Some(((e, s), _)) => excluded_halves > *e || (excluded_halves == *e && sens > *s),
        };
        if better {
            best = Some(((excluded_halves, sens), (lo_half, hi_half)));
        }
    }
    best.map(|(_, halves)| halves)
}

/// Runs the inclusion-based search (see the module doc).
pub(crate) fn solve(problem: &Problem, s: &Settings) -> Outcome {
    let mut heap = BinaryHeap::new();
    let mut seq = 0u64;
    heap.push(Entry {
        domain: Domain {
            t: [0.0, s.tmax],
            u: [0.0, 1.0],
            v: [0.0, 1.0],
        },
        seq,
    });
    // Exclude only if the exact squared distance of the inclusion box to the origin exceeds δ²:
    // the factor absorbs the rounding of the three squares, their sum and δ² itself.
    let delta_sq_bound = s.delta * s.delta * (1.0 + 8.0 * f64::EPSILON);
    let mut iterations = 0;
    while let Some(Entry { domain: b, .. }) = heap.pop() {
        if iterations >= s.max_iterations {
            return Outcome {
                toi: Some(b.t[0]),
                iterations,
            };
        }
        iterations += 1;
        // Point–triangle: the box lies entirely outside the triangle (u + v > 1 everywhere). The
        // float sum can only round down to 1 when the exact sum is ≥ 1, so this never drops a box
        // that touches the triangle.
        if problem.stencil == Stencil::PointTriangle && b.u[0] + b.v[0] > 1.0 {
            continue;
        }
        let f = problem.corners(&b);
        let (excluded, width) = assess(&f, &problem.err, s.delta, delta_sq_bound);
        if excluded {
            continue;
        }
        // Accept (report an impact at this box's start, which is no later than any root since
        // every remaining box starts at least as late) when either the inclusion is narrower than
        // the tolerance, or a corner at the box's start time is an actual configuration within
        // `δ + tolerance` (so the reported time itself is within the tolerance of contact). The
        // second rule only decides *whether* to report; its false positives are near misses
        // within the tolerance, as for the first. It keeps tangential approaches with `δ > 0`
        // from being refined to the tolerance over the whole region that is that close.
        let must_refine = s.no_zero_toi && b.t[0] == 0.0;
        if !must_refine {
            let narrow = width <= s.tolerance;
            let near_corner = (0..4).any(|c| {
                let inside = problem.stencil == Stencil::EdgeEdge || b.u[(c >> 1) & 1] + b.v[c & 1] <= 1.0;
                inside && dot(&f[c], &f[c]).sqrt() <= s.delta + s.tolerance
            });
            if narrow || near_corner {
                return Outcome {
                    toi: Some(b.t[0]),
                    iterations,
                };
            }
        }
        // First try to cut off the part of the box before its predicted first approach.
        if let Some(n) = mean_direction(&f) {
            if let Some(t_split) = directional_time_split(&b, &f, &problem.err, s.delta, &n) {
                let mut lower = b;
                let mut upper = b;
                lower.t[1] = t_split;
                upper.t[0] = t_split;
                iterations += 1;
                let fl = problem.corners(&lower);
                let lower_excluded = excluded_along(&fl, &problem.err, s.delta, &n)
                    || assess(&fl, &problem.err, s.delta, delta_sq_bound).0;
                for (half, keep) in [(lower, !lower_excluded), (upper, true)] {
                    if keep {
                        seq += 1;
                        heap.push(Entry { domain: half, seq });
                    }
                }
                continue;
            }
        }
        match choose_split(problem, &b, &f, s.delta, delta_sq_bound) {
            Some((lo_half, hi_half)) => {
                for half in [lo_half, hi_half] {
                    seq += 1;
                    heap.push(Entry { domain: half, seq });
                }
            }
            // At floating-point resolution in every parameter.
            None => {
                return Outcome {
                    toi: Some(b.t[0]),
                    iterations,
                }
            }
        }
    }
    Outcome { toi: None, iterations }
}
