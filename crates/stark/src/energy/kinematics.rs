//! The kinematic map from DOF velocities to world positions (DESIGN §2, paper eq. 1).
//!
//! Energies are functions of world positions `x` of their nodes. A deformable node is at
//! `x = x0 + dt·v` (`∂x/∂v = dt·I`). A point `p` (body-local, relative to the centre of mass) of
//! a rigid body is at `x = t + R(q)·p` with `t = t0 + dt·v` and
//! `q = normalize(q0 + ½·dt·(0, ω) ⊗ q0)`, so it depends on the body's linear and angular
//! velocity blocks, non-linearly on `ω`. [`BodyPose`] holds the trial pose with the first and
//! second derivatives of `R` with respect to `ω`; [`map_element`] applies the chain rule
//! `∇ᵥ = Jᵀ∇ₓ`, `Hᵥ = JᵀHₓJ + Σ (∇ₓ)ₖ ∂²xₖ/∂ω²` to an element's position-space derivatives.

use super::dual::HyperDual;
use super::psd::project_psd;
use crate::state::{
    angular_block, linear_block, positions_from_velocities, rigid_body_of, BodyArrays, NodeArrays, NO_DOF,
};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

// The pose type lives with the state it is part of; its constructors are the kinematic map's.
pub use crate::state::BodyPose;

impl BodyPose {
    /// The pose at rest (`v = ω = 0`): the start-of-step pose.
    pub fn at_rest(t0: Vector3<f64>, q0: &UnitQuaternion<f64>, dt: f64) -> Self {
        Self::new(t0, q0, &Vector3::zeros(), &Vector3::zeros(), dt)
    }

    /// The end-of-step pose for velocities `v` (m/s) and `ω` (rad/s) over `dt` (s).
    pub fn new(t0: Vector3<f64>, q0: &UnitQuaternion<f64>, v: &Vector3<f64>, w: &Vector3<f64>, dt: f64) -> Self {
        // `R = B(q)/n(q)` of the unnormalised `q = q0 + ½·dt·(0, ω) ⊗ q0`, linear in `ω`
        // (`∂q/∂ω_k = p_k`), with `B_ij(q) = β_ij(q, q)` quadratic and `n = q·q`; the
        // derivatives in closed form (the quotient rule twice), a tenth of hyper-duals' work.
        let (w0, u) = (q0.w, q0.imag());
        let h = 0.5 * dt;
        let q = [
            w0 - h * w.dot(&u),
            u.x + h * (w.x * w0 + (w.y * u.z - w.z * u.y)),
            u.y + h * (w.y * w0 + (w.z * u.x - w.x * u.z)),
            u.z + h * (w.z * w0 + (w.x * u.y - w.y * u.x)),
        ];
        // (0, e_k) ⊗ (w0, u) = (−u_k, w0·e_k + e_k × u), times h.
        let p = [
            [-h * u.x, h * w0, -h * u.z, h * u.y],
            [-h * u.y, h * u.z, h * w0, -h * u.x],
            [-h * u.z, -h * u.y, h * u.x, h * w0],
        ];
        let dot = |a: &[f64; 4], b: &[f64; 4]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
        let n = dot(&q, &q);
        let b = rotation_bilinear(&q, &q);
        // First derivatives of B and n along p_k.
        let db: [Matrix3<f64>; 3] = std::array::from_fn(|k| 2.0 * rotation_bilinear(&q, &p[k]));
        let dn: [f64; 3] = std::array::from_fn(|k| 2.0 * dot(&q, &p[k]));
        let (inv_n, inv_n2) = (1.0 / n, 1.0 / (n * n));
        let mut pose = BodyPose {
            t: t0 + v * dt,
            r: b * inv_n,
            dr: std::array::from_fn(|k| db[k] * inv_n - b * (dn[k] * inv_n2)),
            d2r: [[Matrix3::zeros(); 3]; 3],
        };
        for k in 0..3 {
            for l in k..3 {
                let d2b = 2.0 * rotation_bilinear(&p[k], &p[l]);
                let d2n = 2.0 * dot(&p[k], &p[l]);
                let d2r = d2b * inv_n - (db[k] * dn[l] + db[l] * dn[k]) * inv_n2 - b * (d2n * inv_n2)
                    + b * (2.0 * dn[k] * dn[l] * inv_n2 * inv_n);
                pose.d2r[k][l] = d2r;
                pose.d2r[l][k] = d2r;
            }
        }
        pose
    }
}

/// The symmetric bilinear forms `β_ij(a, b)` of quaternions `(w, x, y, z)` with
/// `β_ij(q, q) = n(q)·R_ij(q)`, the rotation matrix of `q` times its squared norm.
fn rotation_bilinear(a: &[f64; 4], b: &[f64; 4]) -> Matrix3<f64> {
    let [aw, ax, ay, az] = *a;
    let [bw, bx, by, bz] = *b;
    let (ww, xx, yy, zz) = (aw * bw, ax * bx, ay * by, az * bz);
    let (xy, xz, yz) = (ax * by + ay * bx, ax * bz + az * bx, ay * bz + az * by);
    let (wx, wy, wz) = (ax * bw + aw * bx, ay * bw + aw * by, az * bw + aw * bz);
    Matrix3::new(
        ww + xx - yy - zz,
        xy - wz,
        xz + wy,
        xy + wz,
        ww - xx + yy - zz,
        yz - wx,
        xz - wy,
        yz + wx,
        ww - xx - yy + zz,
    )
}

/// The kinematic map (DESIGN §2): body poses and all node positions from the DOF velocities `v`.
pub fn apply_kinematic_map(
    nodes: &NodeArrays,
    bodies: &BodyArrays,
    v: &[Vector3<f64>],
    dt: f64,
    x: &mut Vec<Vector3<f64>>,
    poses: &mut Vec<BodyPose>,
) {
    let n = nodes.len();
    poses.clear();
    poses.extend((0..bodies.len()).map(|b| {
        BodyPose::new(
            bodies.position[b],
            &bodies.orientation[b],
            &v[linear_block(n, b) as usize],
            &v[angular_block(n, b) as usize],
            dt,
        )
    }));
    positions_from_velocities(nodes, v, dt, x);
    if !bodies.is_empty() {
        for (i, &b) in nodes.body.iter().enumerate() {
            if let Some(b) = rigid_body_of(b) {
                x[i] = poses[b].point(&nodes.rest[i]);
            }
        }
    }
}

/// The integrated orientation `normalize(q0 + ½·dt·(0, ω) ⊗ q0)` (DESIGN §2).
pub fn integrate_orientation(q0: &UnitQuaternion<f64>, w: &Vector3<f64>, dt: f64) -> UnitQuaternion<f64> {
    let q = q0.quaternion() + Quaternion::from_parts(0.0, *w) * q0.quaternion() * (0.5 * dt);
    UnitQuaternion::from_quaternion(q)
}

/// How one element node depends on the DOFs.
#[derive(Clone, Copy, Debug)]
pub enum NodeMap<'a> {
    /// A deformable node: `x = x0 + dt·v` of DOF block `block`.
    Free {
        /// DOF block.
        block: u32,
    },
    /// A rigid-body point `x = t + R·p`.
    Rigid {
        /// Linear velocity block.
        lin: u32,
        /// Angular velocity block.
        ang: u32,
        /// Body-local point, m.
        local: Vector3<f64>,
        /// Trial pose of the body.
        pose: &'a BodyPose,
    },
    /// The body's angular velocity itself (`x = ω`, identity Jacobian).
    AngularVelocity {
        /// Angular velocity block.
        ang: u32,
    },
    /// Padding: depends on no DOF.
    Fixed,
}

impl NodeMap<'_> {
    /// Whether the map is `dt·I` on one block.
    #[inline]
    pub fn is_free(&self) -> bool {
        matches!(self, NodeMap::Free { .. })
    }

    fn blocks(&self) -> ([u32; 2], usize) {
        match *self {
            NodeMap::Free { block } => ([block, NO_DOF], 1),
            NodeMap::Rigid { lin, ang, .. } => ([lin, ang], 2),
            NodeMap::AngularVelocity { ang } => ([ang, NO_DOF], 1),
            NodeMap::Fixed => ([NO_DOF, NO_DOF], 0),
        }
    }
}

/// The distinct DOF blocks of an element, in order of first appearance, padded with [`NO_DOF`];
/// returns their count.
pub fn element_blocks(maps: &[NodeMap], out: &mut [u32]) -> usize {
    out.iter_mut().for_each(|o| *o = NO_DOF);
    let mut n = 0;
    for m in maps {
        let (b, k) = m.blocks();
        for &blk in &b[..k] {
            if !out[..n].contains(&blk) {
                out[n] = blk;
                n += 1;
            }
        }
    }
    n
}

/// Number of distinct DOF blocks of an element.
pub fn count_blocks(maps: &[NodeMap]) -> usize {
    let mut buf = [NO_DOF; 16];
    element_blocks(maps, &mut buf[..(2 * maps.len()).min(16)])
}

/// How [`map_element`] makes the DOF Hessian positive semi-definite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapProjection {
    /// Keep the exact Hessian.
    None,
    /// Project the whole DOF Hessian (including the second-order rotation terms).
    Full,
    /// The position-space Hessian is already positive semi-definite, so `JᵀHJ` is too: project
    /// only each body's 3×3 second-order rotation term (cheap; a sum of PSD parts is PSD).
    SecondOrderOnly,
}

/// Write position-space derivatives of an element whose nodes are all deformable, in stencil
/// order, in DOF space: `∂x/∂v = dt·I`, so `∇ᵥ = dt ∇ₓ` and `Hᵥ = dt² Hₓ`, into the layout
/// [`element_stride`](super::term::element_stride)`(width)` (the width from `out`'s length; the
/// entries of slots beyond `N` are zero).
#[inline]
pub fn write_deformable_element<const N: usize>(d: &HyperDual<N>, dt: f64, out: &mut [f64]) {
    let width = super::term::width_of_stride(out.len());
    let n = 3 * N;
    if width > N {
        out[1 + n..].iter_mut().for_each(|o| *o = 0.0);
    }
    out[0] = d.value;
    for (k, g) in d.grad.as_flattened().iter().enumerate() {
        out[1 + k] = dt * g;
    }
    let dt2 = dt * dt;
    let h = d.hess.as_flattened().as_flattened().as_flattened();
    let base = 1 + 3 * width;
    for a in 0..N {
        for b in 0..N {
            let block = &mut out[base + 9 * (a * width + b)..][..9];
            for i in 0..3 {
                for j in 0..3 {
                    block[3 * i + j] = dt2 * h[(3 * a + i) * n + 3 * b + j];
                }
            }
        }
    }
}

/// Where a closed-form element derivative writes, node block by node block: the hyper-dual
/// layout ([`HyperDual`], position space) or an element row in DOF space ([`DeformableRow`]).
pub trait DerivativeSink {
    /// The element's energy, J.
    fn set_value(&mut self, value: f64);
    /// Node `a`'s gradient with respect to its position.
    fn set_gradient(&mut self, a: usize, g: &Vector3<f64>);
    /// Hessian block `(a, b)`, `a ≤ b`, with respect to the positions of nodes `a` and `b`; block
    /// `(b, a)` is its transpose. A diagonal block (`a = b`) is taken from its lower triangle.
    fn set_hessian_pair(&mut self, a: usize, b: usize, block: &Matrix3<f64>);
}

impl<const N: usize> DerivativeSink for HyperDual<N> {
    #[inline(always)]
    fn set_value(&mut self, value: f64) {
        self.value = value;
    }
    #[inline(always)]
    fn set_gradient(&mut self, a: usize, g: &Vector3<f64>) {
        self.grad[a] = [g.x, g.y, g.z];
    }
    #[inline(always)]
    fn set_hessian_pair(&mut self, a: usize, b: usize, block: &Matrix3<f64>) {
        for i in 0..3 {
            for k in 0..3 {
                self.hess[a][i][b][k] = block[(i, k)];
                self.hess[b][k][a][i] = block[(i, k)];
            }
        }
    }
}

/// The element row of [`write_deformable_element`] written block by block, with no hyper-dual
/// in between: `∇ᵥ = dt ∇ₓ`, `Hᵥ = dt² Hₓ` (all nodes deformable, in stencil order).
pub struct DeformableRow<'a> {
    out: &'a mut [f64],
    width: usize,
    dt: f64,
}

impl<'a> DeformableRow<'a> {
    /// A row of `n_nodes` nodes over `out` (layout
    /// [`element_stride`](super::term::element_stride)`(width)`, width from its length): the
    /// gradient of the padding slots beyond `n_nodes` is zeroed here (their Hessian blocks are
    /// never read); the caller writes every node's value, gradient and Hessian pairs.
    pub fn new(n_nodes: usize, dt: f64, out: &'a mut [f64]) -> Self {
        let width = super::term::width_of_stride(out.len());
        out[1 + 3 * n_nodes..1 + 3 * width].iter_mut().for_each(|o| *o = 0.0);
        DeformableRow { out, width, dt }
    }
}

impl DerivativeSink for DeformableRow<'_> {
    #[inline(always)]
    fn set_value(&mut self, value: f64) {
        self.out[0] = value;
    }
    #[inline(always)]
    fn set_gradient(&mut self, a: usize, g: &Vector3<f64>) {
        for i in 0..3 {
            self.out[1 + 3 * a + i] = self.dt * g[i];
        }
    }
    #[inline(always)]
    fn set_hessian_pair(&mut self, a: usize, b: usize, block: &Matrix3<f64>) {
        let (w, dt2) = (self.width, self.dt * self.dt);
        let base = 1 + 3 * w;
        let ab = &mut self.out[base + 9 * (a * w + b)..][..9];
        for i in 0..3 {
            for k in 0..3 {
                // A diagonal block is made exactly symmetric from its lower triangle.
                ab[3 * i + k] = dt2
                    * if a == b {
                        block[(i.max(k), i.min(k))]
                    } else {
                        block[(i, k)]
                    };
            }
        }
        if a != b {
            let ba = &mut self.out[base + 9 * (b * w + a)..][..9];
            for i in 0..3 {
                for k in 0..3 {
                    ba[3 * k + i] = dt2 * block[(i, k)];
                }
            }
        }
    }
}

/// [`write_deformable_element`] for a stencil with nodes that have no DOFs: node `a` goes to
/// block slot `slots[a]`, `None` for a node without DOFs.
pub fn write_deformable_element_in_slots<const N: usize>(
    d: &HyperDual<N>,
    slots: &[Option<usize>; N],
    dt: f64,
    out: &mut [f64],
) {
    let width = super::term::width_of_stride(out.len());
    // The value and gradient are read whole (the gradient's magnitude); of the Hessian only the
    // blocks between the element's own slots, all written below: the rest may keep old values.
    out[..1 + 3 * width].iter_mut().for_each(|o| *o = 0.0);
    out[0] = d.value;
    let dt2 = dt * dt;
    let base = 1 + 3 * width;
    for (a, sa) in slots.iter().enumerate() {
        let Some(sa) = *sa else { continue };
        for i in 0..3 {
            out[1 + 3 * sa + i] = dt * d.grad[a][i];
        }
        for (b, sb) in slots.iter().enumerate() {
            let Some(sb) = *sb else { continue };
            let block = &mut out[base + 9 * (sa * width + sb)..][..9];
            for i in 0..3 {
                for j in 0..3 {
                    block[3 * i + j] = dt2 * d.hess[a][i][b][j];
                }
            }
        }
    }
}

/// A node's Jacobian `∂x/∂(block)`: `s·I` (a deformable node's or a rigid body's linear block:
/// `dt·I`) or a full matrix (a rigid point's angular block). The identity's products are skipped.
#[derive(Clone, Copy)]
enum Jacobian {
    Scaled(f64),
    Full(Matrix3<f64>),
}

impl Jacobian {
    /// `Jᵀ m`.
    #[inline(always)]
    fn transpose_times<C: nalgebra::Dim, S: nalgebra::storage::Storage<f64, nalgebra::U3, C>>(
        &self,
        m: &nalgebra::Matrix<f64, nalgebra::U3, C, S>,
    ) -> nalgebra::OMatrix<f64, nalgebra::U3, C>
    where
        nalgebra::DefaultAllocator: nalgebra::allocator::Allocator<nalgebra::U3, C>,
    {
        match self {
            Jacobian::Scaled(s) => m * *s,
            Jacobian::Full(j) => j.transpose() * m,
        }
    }
    /// `m J`.
    #[inline(always)]
    fn right_of(&self, m: &Matrix3<f64>) -> Matrix3<f64> {
        match self {
            Jacobian::Scaled(s) => m * *s,
            Jacobian::Full(j) => m * j,
        }
    }
}

/// Map position-space derivatives of an element (value, gradient and full Hessian of `d`) to its
/// DOF blocks (see [`element_blocks`]), writing the solver layout of
/// [`element_stride`](super::term::element_stride)`(width)` into `out`, with the Hessian made
/// positive semi-definite as `projection` says.
pub fn map_element<const N: usize>(
    maps: &[NodeMap; N],
    d: &HyperDual<N>,
    dt: f64,
    width: usize,
    projection: MapProjection,
    out: &mut [f64],
) {
    let mut blocks = [NO_DOF; 8];
    let m = element_blocks(maps, &mut blocks[..2 * N]);
    debug_assert!(m <= width);
    let slot = |b: u32| blocks[..m].iter().position(|&x| x == b).expect("block of the element");
    // Per node: up to two (slot, Jacobian) pairs; most Jacobians are multiples of the identity.
    let none = (usize::MAX, Jacobian::Scaled(0.0));
    let jac: [[(usize, Jacobian); 2]; N] = std::array::from_fn(|a| match maps[a] {
        NodeMap::Free { block } => [(slot(block), Jacobian::Scaled(dt)), none],
        NodeMap::Rigid { lin, ang, local, pose } => [
            (slot(lin), Jacobian::Scaled(dt)),
            (slot(ang), Jacobian::Full(pose.point_jacobian_w(&local))),
        ],
        NodeMap::AngularVelocity { ang } => [(slot(ang), Jacobian::Scaled(1.0)), none],
        NodeMap::Fixed => [none, none],
    });
    let n = 3 * m;
    // At most 2 blocks per node and 4 nodes: 8 blocks, 24 DOFs.
    debug_assert!(m <= 8, "elements of more than 4 nodes are not mapped");
    let mut second = [[0.0; 9]; 8];
    let mut g = [0.0; 24];
    let mut h = [0.0; 24 * 24];
    for a in 0..N {
        let ga = Vector3::from(d.grad[a]);
        for &(s, j) in &jac[a] {
            if s == usize::MAX {
                continue;
            }
            let gs = j.transpose_times(&ga);
            for i in 0..3 {
                g[3 * s + i] += gs[i];
            }
        }
        for b in 0..N {
            let hab = Matrix3::from_fn(|i, k| d.hess[a][i][b][k]);
            for &(sa, ja) in &jac[a] {
                if sa == usize::MAX {
                    continue;
                }
                let left = ja.transpose_times(&hab);
                for &(sb, jb) in &jac[b] {
                    if sb == usize::MAX {
                        continue;
                    }
                    let blk = jb.right_of(&left);
                    for i in 0..3 {
                        for k in 0..3 {
                            h[(3 * sa + i) * n + 3 * sb + k] += blk[(i, k)];
                        }
                    }
                }
            }
        }
        // Second-order term of the rotation: Σᵢ gᵢ ∂²xᵢ/∂ω_k∂ω_l (collected per angular slot
        // when it is projected on its own).
        if let NodeMap::Rigid { ang, local, pose, .. } = maps[a] {
            let s = slot(ang);
            for k in 0..3 {
                for l in 0..3 {
                    second[s][3 * k + l] += ga.dot(&(pose.d2r[k][l] * local));
                }
            }
        }
    }
    for (s, block) in second.iter_mut().enumerate().take(m) {
        if block.iter().all(|&v| v == 0.0) {
            continue;
        }
        if projection == MapProjection::SecondOrderOnly {
            project_psd(block, 3);
        }
        for k in 0..3 {
            for l in 0..3 {
                h[(3 * s + k) * n + 3 * s + l] += block[3 * k + l];
            }
        }
    }
    if projection == MapProjection::Full {
        project_psd(&mut h[..n * n], n);
    }
    out.iter_mut().for_each(|o| *o = 0.0);
    out[0] = d.value;
    out[1..1 + n].copy_from_slice(&g[..n]);
    let base = 1 + 3 * width;
    for a in 0..m {
        for b in 0..m {
            let blk = &mut out[base + 9 * (a * width + b)..base + 9 * (a * width + b) + 9];
            for i in 0..3 {
                for k in 0..3 {
                    blk[3 * i + k] = h[(3 * a + i) * n + 3 * b + k];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::scalar::Scalar;

    fn pose_at(w: &Vector3<f64>) -> (BodyPose, UnitQuaternion<f64>) {
        let q0 = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1);
        (
            BodyPose::new(Vector3::new(1.0, 2.0, 3.0), &q0, &Vector3::zeros(), w, 0.01),
            q0,
        )
    }

    #[test]
    fn rotation_matches_integrated_quaternion() {
        let w = Vector3::new(3.0, -20.0, 7.0);
        let (pose, q0) = pose_at(&w);
        let q = integrate_orientation(&q0, &w, 0.01);
        assert!((pose.r - q.to_rotation_matrix().into_inner()).norm() < 1e-14);
    }

    #[test]
    fn rotation_derivatives_match_finite_differences() {
        let w = Vector3::new(3.0, -20.0, 7.0);
        let (pose, _) = pose_at(&w);
        let h = 1e-5;
        for k in 0..3 {
            let mut wp = w;
            wp[k] += h;
            let mut wm = w;
            wm[k] -= h;
            let (pp, _) = pose_at(&wp);
            let (pm, _) = pose_at(&wm);
            let fd = (pp.r - pm.r) / (2.0 * h);
            assert!((fd - pose.dr[k]).norm() < 1e-9 * pose.dr[k].norm().max(1.0), "dR/dw{k}");
            for l in 0..3 {
                let fd2 = (pp.dr[l] - pm.dr[l]) / (2.0 * h);
                assert!((fd2 - pose.d2r[k][l]).norm() < 1e-7, "d2R/dw{k}dw{l}");
            }
        }
    }

    #[test]
    fn mapped_derivatives_match_finite_differences() {
        // E = ½‖x_a − x_b‖² + (x_a·c)³ for a rigid point a and a deformable node b.
        let c = Vector3::new(0.3, -0.2, 0.5);
        let p = Vector3::new(0.1, -0.2, 0.3);
        let xb0 = Vector3::new(1.5, 1.0, 2.0);
        let dt = 0.01;
        let q0 = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1);
        let t0 = Vector3::new(1.0, 2.0, 3.0);
        // DOFs: [v_body, w_body, v_node] (blocks 0, 1, 2).
        let energy = |u: &[f64; 9]| -> f64 {
            let v = Vector3::new(u[0], u[1], u[2]);
            let w = Vector3::new(u[3], u[4], u[5]);
            let pose = BodyPose::new(t0, &q0, &v, &w, dt);
            let xa = pose.point(&p);
            let xb = xb0 + Vector3::new(u[6], u[7], u[8]) * dt;
            0.5 * (xa - xb).norm_squared() + xa.dot(&c).powi(3)
        };
        let u = [0.5, -1.0, 2.0, 4.0, -3.0, 6.0, 1.0, 0.2, -0.3];
        let v = Vector3::new(u[0], u[1], u[2]);
        let w = Vector3::new(u[3], u[4], u[5]);
        let pose = BodyPose::new(t0, &q0, &v, &w, dt);
        let xa = pose.point(&p);
        let xb = xb0 + Vector3::new(u[6], u[7], u[8]) * dt;
        let xs = HyperDual::<2>::variables(&[xa, xb]);
        let diff = [
            xs[0].0[0] - xs[1].0[0],
            xs[0].0[1] - xs[1].0[1],
            xs[0].0[2] - xs[1].0[2],
        ];
        let dot = xs[0].0[0] * c.x + xs[0].0[1] * c.y + xs[0].0[2] * c.z;
        let mut d = (diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2]) * 0.5 + dot * dot * dot;
        crate::energy::potential::symmetrize(&mut d);
        let maps = [
            NodeMap::Rigid {
                lin: 0,
                ang: 1,
                local: p,
                pose: &pose,
            },
            NodeMap::Free { block: 2 },
        ];
        let width = 3;
        let mut out = vec![0.0; crate::energy::term::element_stride(width)];
        map_element(&maps, &d, dt, width, MapProjection::None, &mut out);
        let h = 1e-6;
        for i in 0..9 {
            let mut up = u;
            up[i] += h;
            let mut um = u;
            um[i] -= h;
            let fd = (energy(&up) - energy(&um)) / (2.0 * h);
            assert!(
                (fd - out[1 + i]).abs() < 1e-6 * fd.abs().max(1e-3),
                "gradient {i}: {fd} vs {}",
                out[1 + i]
            );
        }
        // Hessian by differences of the mapped gradient.
        let grad_at = |u: &[f64; 9]| -> Vec<f64> {
            let v = Vector3::new(u[0], u[1], u[2]);
            let w = Vector3::new(u[3], u[4], u[5]);
            let pose = BodyPose::new(t0, &q0, &v, &w, dt);
            let xa = pose.point(&p);
            let xb = xb0 + Vector3::new(u[6], u[7], u[8]) * dt;
            let xs = HyperDual::<2>::variables(&[xa, xb]);
            let diff = [
                xs[0].0[0] - xs[1].0[0],
                xs[0].0[1] - xs[1].0[1],
                xs[0].0[2] - xs[1].0[2],
            ];
            let dot = xs[0].0[0] * c.x + xs[0].0[1] * c.y + xs[0].0[2] * c.z;
            let mut d = (diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2]) * 0.5 + dot * dot * dot;
            crate::energy::potential::symmetrize(&mut d);
            let maps = [
                NodeMap::Rigid {
                    lin: 0,
                    ang: 1,
                    local: p,
                    pose: &pose,
                },
                NodeMap::Free { block: 2 },
            ];
            let mut out = vec![0.0; crate::energy::term::element_stride(3)];
            map_element(&maps, &d, dt, 3, MapProjection::None, &mut out);
            out[1..10].to_vec()
        };
        let base = 1 + 3 * width;
        for i in 0..9 {
            let mut up = u;
            up[i] += h;
            let mut um = u;
            um[i] -= h;
            let (gp, gm) = (grad_at(&up), grad_at(&um));
            for j in 0..9 {
                let fd = (gp[j] - gm[j]) / (2.0 * h);
                let (bi, bj) = (i / 3, j / 3);
                let exact = out[base + 9 * (bj * width + bi) + 3 * (j % 3) + i % 3];
                assert!(
                    (fd - exact).abs() < 1e-5 * fd.abs().max(1e-2),
                    "H[{j}][{i}]: {fd} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn rotation_term_projection_is_psd_and_keeps_the_gradient() {
        // A barrier-like element: a rigid point pushed along +z by a deformable node (gradient
        // along −z, position Hessian c·n nᵀ, positive semi-definite), far from the centre of
        // mass so that the second-order rotation term is large and indefinite.
        let dt = 0.05;
        let q0 = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1);
        let pose = BodyPose::new(
            Vector3::new(0.0, 0.0, 1.0),
            &q0,
            &Vector3::zeros(),
            &Vector3::new(1.0, -2.0, 0.5),
            dt,
        );
        let mut d = HyperDual::<2>::constant(0.3);
        d.grad[0] = [0.0, 0.0, -50.0];
        d.grad[1] = [0.0, 0.0, 50.0];
        for (a, b, s) in [(0, 0, 1.0), (1, 1, 1.0), (0, 1, -1.0), (1, 0, -1.0)] {
            d.hess[a][2][b][2] = 2.0e3 * s;
        }
        let rigid = [
            NodeMap::Rigid {
                lin: 0,
                ang: 1,
                local: Vector3::new(0.4, -0.3, -0.5),
                pose: &pose,
            },
            NodeMap::Free { block: 2 },
        ];
        let width = 3;
        let stride = crate::energy::term::element_stride(width);
        let (mut exact, mut split, mut full) = (vec![0.0; stride], vec![0.0; stride], vec![0.0; stride]);
        map_element(&rigid, &d, dt, width, MapProjection::None, &mut exact);
        map_element(&rigid, &d, dt, width, MapProjection::SecondOrderOnly, &mut split);
        map_element(&rigid, &d, dt, width, MapProjection::Full, &mut full);
        assert_eq!(exact[..10], split[..10], "value and gradient");
        let dense = |out: &[f64]| {
            nalgebra::DMatrix::from_fn(9, 9, |i, j| {
                out[1 + 3 * width + 9 * ((i / 3) * width + j / 3) + 3 * (i % 3) + j % 3]
            })
        };
        let min_eig = |m: nalgebra::DMatrix<f64>| m.symmetric_eigenvalues().min();
        assert!(
            min_eig(dense(&exact)) < -1e-3,
            "the test needs an indefinite rotation term"
        );
        assert!(min_eig(dense(&split)) > -1e-9 * dense(&split).norm());
        assert!(min_eig(dense(&full)) > -1e-9 * dense(&full).norm());
        // Without rigid nodes nothing is projected.
        let free = [NodeMap::Free { block: 0 }, NodeMap::Free { block: 1 }];
        let (mut a, mut b) = (vec![0.0; stride], vec![0.0; stride]);
        map_element(&free, &d, dt, width, MapProjection::None, &mut a);
        map_element(&free, &d, dt, width, MapProjection::SecondOrderOnly, &mut b);
        assert_eq!(a, b);
    }
}
