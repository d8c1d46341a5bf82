//! The contact objects and the tables over their pairs: which pairs collide, their friction
//! coefficients and their barrier thickness.

use super::pairs::ContactPair;
use super::{Contact, ContactHandle, ContactObject};
use crate::error::{check_param, Result, StarkError};
use crate::state::NodeSetHandle;
use nalgebra::Vector3;

pub(super) fn sorted_objects([a, b]: [u16; 2]) -> [u16; 2] {
    if a < b {
        [a, b]
    } else {
        [b, a]
    }
}

pub(super) fn sorted2(a: u32, b: u32) -> [u32; 2] {
    if a < b {
        [a, b]
    } else {
        [b, a]
    }
}

impl Contact {
    /// Contact objects.
    pub fn objects(&self) -> &[ContactObject] {
        &self.objects
    }

    /// Active barrier pairs at the last evaluation.
    pub fn pairs(&self) -> &[ContactPair] {
        &self.pairs
    }

    /// The largest barrier stiffness κ of any pair of objects, N/m (0 before the first step).
    pub fn stiffness(&self) -> f64 {
        self.kappa.max()
    }

    /// Barrier stiffness κ between two objects, N/m (0 before the first step that needs it).
    pub fn pair_stiffness(&self, a: ContactHandle, b: ContactHandle) -> Result<f64> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        Ok(self.kappa.get(i, j))
    }

    /// Register the surface of an object (indices local to `nodes`): its triangles, its edges
    /// and the nodes that act as contact points. Self-contact is on.
    pub fn add_object(
        &mut self,
        label: &str,
        nodes: NodeSetHandle,
        rest: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        edges: &[[usize; 2]],
        points: &[usize],
        thickness_m: f64,
    ) -> Result<ContactHandle> {
        check_param(
            label,
            "contact thickness_m",
            thickness_m,
            thickness_m > 0.0 && thickness_m.is_finite(),
            "must be positive (m)",
        )?;
        if self.objects.len() >= u16::MAX as usize {
            return Err(StarkError::InvalidInput("too many contact objects".into()));
        }
        let n = nodes.len as usize;
        let bad = triangles
            .iter()
            .flatten()
            .chain(edges.iter().flatten())
            .chain(points)
            .find(|&&i| i >= n);
        if let Some(&i) = bad {
            return Err(StarkError::InvalidInput(format!(
                "contact surface of '{label}' refers to node {i}, but the object has {n} nodes"
            )));
        }
        let id = self.objects.len() as u16;
        let g = |i: usize| nodes.global(i) as u32;
        self.points.extend(points.iter().map(|&p| g(p)));
        self.point_obj.extend(std::iter::repeat_n(id, points.len()));
        self.edges.extend(edges.iter().map(|e| [g(e[0]), g(e[1])]));
        self.edge_obj.extend(std::iter::repeat_n(id, edges.len()));
        self.edge_rest_len_sq.extend(
            edges
                .iter()
                .map(|e| (rest[nodes.global(e[1])] - rest[nodes.global(e[0])]).norm_squared()),
        );
        self.triangles
            .extend(triangles.iter().map(|t| [g(t[0]), g(t[1]), g(t[2])]));
        self.tri_obj.extend(std::iter::repeat_n(id, triangles.len()));
        self.objects.push(ContactObject {
            label: label.to_string(),
            thickness_m,
            nodes,
        });
        // Grow the pair tables: everything collides, frictionless, until told otherwise.
        let m = self.objects.len();
        let mut enabled = vec![true; m * m];
        let mut friction = vec![0.0; m * m];
        for a in 0..m - 1 {
            for b in 0..m - 1 {
                enabled[a * m + b] = self.enabled[a * (m - 1) + b];
                friction[a * m + b] = self.friction[a * (m - 1) + b];
            }
        }
        self.enabled = enabled;
        self.friction = friction;
        self.kappa.resize(m);
        self.version += 1;
        Ok(ContactHandle(id as u32))
    }

    fn check(&self, h: ContactHandle) -> Result<usize> {
        let i = h.0 as usize;
        if i < self.objects.len() {
            Ok(i)
        } else {
            Err(StarkError::InvalidHandle {
                kind: "contact object",
                index: i,
                len: self.objects.len(),
            })
        }
    }

    /// The contact object with this label.
    pub fn object_by_label(&self, label: &str) -> Option<ContactHandle> {
        self.objects
            .iter()
            .position(|o| o.label == label)
            .map(|i| ContactHandle(i as u32))
    }

    /// Friction coefficient μ between two objects (`a == b`: self-friction). Takes effect at the
    /// next step.
    pub fn set_friction(&mut self, a: ContactHandle, b: ContactHandle, mu: f64) -> Result<()> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        check_param(
            &self.objects[i].label,
            "friction",
            mu,
            mu >= 0.0 && mu.is_finite(),
            "must be non-negative",
        )?;
        let m = self.objects.len();
        self.friction[i * m + j] = mu;
        self.friction[j * m + i] = mu;
        Ok(())
    }

    /// Friction coefficient between two objects.
    pub fn friction(&self, a: ContactHandle, b: ContactHandle) -> Result<f64> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        Ok(self.friction[i * self.objects.len() + j])
    }

    /// Switch collisions between two objects (`a == b`: self-collision) off or on.
    pub fn set_collision(&mut self, a: ContactHandle, b: ContactHandle, enabled: bool) -> Result<()> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        let m = self.objects.len();
        self.enabled[i * m + j] = enabled;
        self.enabled[j * m + i] = enabled;
        self.version += 1;
        Ok(())
    }

    /// Whether two objects (`a == b`: an object with itself) collide.
    pub fn collision_enabled(&self, a: ContactHandle, b: ContactHandle) -> Result<bool> {
        let (i, j) = (self.check(a)?, self.check(b)?);
        Ok(self.enabled[i * self.objects.len() + j])
    }

    /// Switch collisions between two objects off (the original's `disable_collision`).
    pub fn disable_collision(&mut self, a: ContactHandle, b: ContactHandle) -> Result<()> {
        self.set_collision(a, b, false)
    }

    /// Change an object's contact thickness, m.
    pub fn set_thickness(&mut self, a: ContactHandle, thickness_m: f64) -> Result<()> {
        let i = self.check(a)?;
        check_param(
            &self.objects[i].label,
            "contact thickness_m",
            thickness_m,
            thickness_m > 0.0 && thickness_m.is_finite(),
            "must be positive (m)",
        )?;
        self.objects[i].thickness_m = thickness_m;
        Ok(())
    }

    pub(super) fn pair_ok(&self, a: u16, b: u16) -> bool {
        self.enabled[a as usize * self.objects.len() + b as usize]
    }

    pub(super) fn dhat(&self, a: u16, b: u16) -> f64 {
        self.objects[a as usize].thickness_m + self.objects[b as usize].thickness_m
    }

    pub(super) fn mu(&self, a: u16, b: u16) -> f64 {
        self.friction[a as usize * self.objects.len() + b as usize]
    }
}
