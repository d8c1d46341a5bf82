//! Ready-made objects: a node set with its inertia, strain, bending and output mesh in one call.

use super::materials::{Bending, LineMaterial, SurfaceMaterial, VolumeMaterial};
use super::meshes;
use crate::contact::ContactHandle;
use crate::deformables::{
    DihedralBendingHandle, FlatBendingHandle, InertiaHandle, NodeSetHandle, PrescribedHandle, PrescribedParams,
    SegmentStrainHandle, TetStrainHandle, TriangleStrainHandle,
};
use crate::error::{Result, StarkError};
use crate::geometry::mesh;
use crate::simulation::Simulation;
use crate::state::{OutputCells, FIXED_NODE};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Handles of a line object.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct LineHandle {
    /// Its nodes.
    pub nodes: NodeSetHandle,
    /// Its inertia.
    pub inertia: InertiaHandle,
    /// Its segment strain.
    pub strain: SegmentStrainHandle,
    /// Its contact object, if it has a contact thickness.
    pub contact: Option<ContactHandle>,
}

/// Bending handle of a surface.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub enum BendingHandle {
    /// Flat bending.
    Flat(FlatBendingHandle),
    /// Discrete-shell bending.
    Dihedral(DihedralBendingHandle),
}

/// Handles of a surface object.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct SurfaceHandle {
    /// Its nodes.
    pub nodes: NodeSetHandle,
    /// Its inertia.
    pub inertia: InertiaHandle,
    /// Its membrane strain.
    pub strain: TriangleStrainHandle,
    /// Its bending, if any.
    pub bending: Option<BendingHandle>,
    /// Its contact object, if it has a contact thickness.
    pub contact: Option<ContactHandle>,
}

/// Handles of a volume object.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct VolumeHandle {
    /// Its nodes.
    pub nodes: NodeSetHandle,
    /// Its inertia.
    pub inertia: InertiaHandle,
    /// Its tet strain.
    pub strain: TetStrainHandle,
    /// Its contact object (its boundary surface), if it has a contact thickness.
    pub contact: Option<ContactHandle>,
}

/// Handles of a kinematic obstacle (a surface whose nodes all follow prescribed targets).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct ObstacleHandle {
    /// Its nodes.
    pub nodes: NodeSetHandle,
    /// The prescribed positions moving it (`set_transform` on this handle moves the obstacle).
    pub prescribed: PrescribedHandle,
    /// Its contact object.
    pub contact: ContactHandle,
}

/// Handles of a fixed obstacle (a surface whose nodes never move: [`FIXED_NODE`]).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct FixedSurfaceHandle {
    /// Its nodes.
    pub nodes: NodeSetHandle,
    /// Its contact object.
    pub contact: ContactHandle,
}

fn per_node(
    n: usize,
    label: &str,
    kind: &'static str,
    elements: impl Iterator<Item = (usize, f64)>,
) -> Result<Vec<f64>> {
    let mut measures = vec![0.0; n];
    for (node, m) in elements {
        if node >= n {
            return Err(StarkError::InvalidInput(format!(
                "a {kind} of '{label}' refers to node {node}, but there are {n} nodes"
            )));
        }
        measures[node] += m;
    }
    Ok(measures)
}

impl Simulation {
    /// Register a contact surface for an object if a thickness is given or defaulted.
    fn register_contact(
        &mut self,
        label: &str,
        nodes: NodeSetHandle,
        triangles: &[[usize; 3]],
        edges: &[[usize; 2]],
        points: &[usize],
        thickness_m: Option<f64>,
    ) -> Result<Option<ContactHandle>> {
        let Some(thickness) = thickness_m.or(self.settings.contact.default_thickness_m) else {
            return Ok(None);
        };
        let rest = self.nodes.rest.clone();
        self.contact
            .add_object(label, nodes, &rest, triangles, edges, points, thickness)
            .map(Some)
    }

    /// A rod or cable: nodes, segment strain and inertia lumped from segment lengths.
    pub fn add_line(
        &mut self,
        label: &str,
        vertices: &[Vector3<f64>],
        segments: &[[usize; 2]],
        material: &LineMaterial,
    ) -> Result<LineHandle> {
        material.inertia.validate(label)?;
        let nodes = self.add_nodes(label, vertices)?;
        let strain = self
            .deformables
            .segments
            .add(&self.nodes, nodes, label, segments, material.strain.clone())?;
        let measures = per_node(
            vertices.len(),
            label,
            "segment",
            segments.iter().flat_map(|s| {
                let l = (vertices[s[0].min(vertices.len() - 1)] - vertices[s[1].min(vertices.len() - 1)]).norm() / 2.0;
                [(s[0], l), (s[1], l)]
            }),
        )?;
        let inertia = self
            .deformables
            .inertia
            .add(nodes, label, &measures, material.inertia.clone())?;
        let points: Vec<usize> = (0..vertices.len()).collect();
        let contact = self.register_contact(label, nodes, &[], segments, &points, material.contact_thickness_m)?;
        self.output
            .add_mesh(label, nodes, OutputCells::Segments(segments.to_vec()));
        Ok(LineHandle {
            nodes,
            inertia,
            strain,
            contact,
        })
    }

    /// A straight line of `n_segments` from `begin` to `end`.
    pub fn add_line_segments(
        &mut self,
        label: &str,
        begin: Vector3<f64>,
        end: Vector3<f64>,
        n_segments: usize,
        material: &LineMaterial,
    ) -> Result<LineHandle> {
        if n_segments == 0 {
            return Err(StarkError::InvalidInput(format!(
                "line '{label}' needs at least one segment"
            )));
        }
        let m = meshes::segment_line(begin, end, n_segments);
        self.add_line(label, &m.vertices, &m.elements, material)
    }

    /// A shell or cloth: nodes, membrane strain, bending and inertia lumped from triangle areas.
    pub fn add_surface(
        &mut self,
        label: &str,
        vertices: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        material: &SurfaceMaterial,
    ) -> Result<SurfaceHandle> {
        material.inertia.validate(label)?;
        let nodes = self.add_nodes(label, vertices)?;
        let strain = self
            .deformables
            .triangles
            .add(&self.nodes, nodes, label, triangles, material.strain.clone())?;
        let bending = match &material.bending {
            Bending::None => None,
            Bending::Flat(p) => Some(BendingHandle::Flat(self.deformables.flat_bending.add(
                &self.nodes,
                nodes,
                label,
                triangles,
                p.clone(),
            )?)),
            Bending::Dihedral(p) => Some(BendingHandle::Dihedral(self.deformables.dihedral_bending.add(
                &self.nodes,
                nodes,
                label,
                triangles,
                p.clone(),
            )?)),
        };
        let measures = per_node(
            vertices.len(),
            label,
            "triangle",
            triangles.iter().flat_map(|t| {
                let a = mesh::triangle_area(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]]) / 3.0;
                [(t[0], a), (t[1], a), (t[2], a)]
            }),
        )?;
        let inertia = self
            .deformables
            .inertia
            .add(nodes, label, &measures, material.inertia.clone())?;
        let points: Vec<usize> = (0..vertices.len()).collect();
        let edges = mesh::edges_from_triangles(triangles);
        let contact = self.register_contact(label, nodes, triangles, &edges, &points, material.contact_thickness_m)?;
        self.output
            .add_mesh(label, nodes, OutputCells::Triangles(triangles.to_vec()));
        Ok(SurfaceHandle {
            nodes,
            inertia,
            strain,
            bending,
            contact,
        })
    }

    /// A rectangular cloth of `size` (m) in the XY plane centred at the origin, with `quads`
    /// quads per side, two triangles each (the original's `add_surface_grid`).
    pub fn add_surface_grid(
        &mut self,
        label: &str,
        size: [f64; 2],
        quads: [usize; 2],
        material: &SurfaceMaterial,
    ) -> Result<SurfaceHandle> {
        if quads.contains(&0) || !(size[0] > 0.0 && size[1] > 0.0) {
            return Err(StarkError::InvalidInput(format!(
                "surface grid '{label}' needs positive size and quad counts, got {size:?} and {quads:?}"
            )));
        }
        let m = meshes::triangle_grid([0.0, 0.0], size, quads, 0.0);
        self.add_surface(label, &m.vertices, &m.elements, material)
    }

    /// A volumetric solid: nodes, tet strain and inertia lumped from tet volumes. The frames show
    /// the tet mesh.
    pub fn add_volume(
        &mut self,
        label: &str,
        vertices: &[Vector3<f64>],
        tets: &[[usize; 4]],
        material: &VolumeMaterial,
    ) -> Result<VolumeHandle> {
        material.inertia.validate(label)?;
        let nodes = self.add_nodes(label, vertices)?;
        let strain = self
            .deformables
            .tets
            .add(&self.nodes, nodes, label, tets, material.strain.clone())?;
        let measures = per_node(
            vertices.len(),
            label,
            "tet",
            tets.iter().flat_map(|t| {
                let v =
                    mesh::tet_signed_volume(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]], &vertices[t[3]]) / 4.0;
                [(t[0], v), (t[1], v), (t[2], v), (t[3], v)]
            }),
        )?;
        let inertia = self
            .deformables
            .inertia
            .add(nodes, label, &measures, material.inertia.clone())?;
        let contact = if material
            .contact_thickness_m
            .or(self.settings.contact.default_thickness_m)
            .is_some()
        {
            let surface = mesh::find_surface_triangles(tets)
                .map_err(|e| StarkError::InvalidInput(format!("surface of '{label}': {e}")))?;
            let edges = mesh::edges_from_triangles(&surface);
            let mut points: Vec<usize> = surface.iter().flatten().copied().collect();
            points.sort_unstable();
            points.dedup();
            self.register_contact(label, nodes, &surface, &edges, &points, material.contact_thickness_m)?
        } else {
            None
        };
        self.output.add_mesh(label, nodes, OutputCells::Tets(tets.to_vec()));
        Ok(VolumeHandle {
            nodes,
            inertia,
            strain,
            contact,
        })
    }

    /// A box of `size` (m) centred at the origin, `hexes` cells per side, 12 tets per cell
    /// around a centre node (the original's `add_volume_grid`).
    pub fn add_volume_grid(
        &mut self,
        label: &str,
        size: [f64; 3],
        hexes: [usize; 3],
        material: &VolumeMaterial,
    ) -> Result<VolumeHandle> {
        if hexes.contains(&0) || !size.iter().all(|s| *s > 0.0) {
            return Err(StarkError::InvalidInput(format!(
                "volume grid '{label}' needs positive size and cell counts, got {size:?} and {hexes:?}"
            )));
        }
        let m = meshes::tet_grid(Vector3::zeros(), Vector3::from(size), hexes);
        self.add_volume(label, &m.vertices, &m.elements, material)
    }

    /// A kinematic obstacle: a triangle surface whose nodes all follow prescribed targets (stiff
    /// springs of `stiffness` N/m, hardened to 1e-4 of the contact thickness). Move it with
    /// `deformables.prescribed.set_transform(handle.prescribed, …)`. Its self-collision is off.
    pub fn add_prescribed_surface(
        &mut self,
        label: &str,
        vertices: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        thickness_m: f64,
        stiffness: f64,
    ) -> Result<ObstacleHandle> {
        let (nodes, contact) = self.add_obstacle_surface(label, vertices, triangles, thickness_m)?;
        let all: Vec<usize> = (0..vertices.len()).collect();
        let params = PrescribedParams {
            stiffness,
            tolerance_m: 1e-4 * thickness_m,
        };
        let prescribed = self
            .deformables
            .prescribed
            .add(&self.nodes, nodes, label, &all, params)?;
        Ok(ObstacleHandle {
            nodes,
            prescribed,
            contact,
        })
    }

    /// A contact surface fixed in the world (a floor, a wall): its nodes never move and are not
    /// unknowns, so the contacts on it couple nothing through the Hessian. Unlike
    /// [`Simulation::add_prescribed_surface`] (nodes held at their targets by a stiff penalty,
    /// which can be moved), it does not give way by a micrometre under load, and a floor under a
    /// towel does not join all the towel's nodes in the linear system (the robot–towel cases:
    /// a tenth of the factorisation's work).
    pub fn add_fixed_surface(
        &mut self,
        label: &str,
        vertices: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        thickness_m: f64,
    ) -> Result<FixedSurfaceHandle> {
        let (nodes, contact) = self.add_obstacle_surface(label, vertices, triangles, thickness_m)?;
        for i in nodes.range() {
            self.nodes.body[i] = FIXED_NODE;
        }
        Ok(FixedSurfaceHandle { nodes, contact })
    }

    /// An obstacle's nodes, its contact object (no self-collision) and its output mesh.
    fn add_obstacle_surface(
        &mut self,
        label: &str,
        vertices: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        thickness_m: f64,
    ) -> Result<(NodeSetHandle, ContactHandle)> {
        let nodes = self.add_nodes(label, vertices)?;
        let all: Vec<usize> = (0..vertices.len()).collect();
        let edges = mesh::edges_from_triangles(triangles);
        let contact = self
            .register_contact(label, nodes, triangles, &edges, &all, Some(thickness_m))?
            .expect("thickness given");
        self.contact.disable_collision(contact, contact)?;
        self.output
            .add_mesh(label, nodes, OutputCells::Triangles(triangles.to_vec()));
        Ok((nodes, contact))
    }

    /// Prescribe the nodes of `set` inside the axis-aligned box of `center` and full `size` (m).
    /// Selecting no node is an error (a box that misses the object is a typo, not an intent).
    pub fn prescribe_in_box(
        &mut self,
        set: NodeSetHandle,
        center: Vector3<f64>,
        size: Vector3<f64>,
        params: PrescribedParams,
    ) -> Result<PrescribedHandle> {
        let label = self.deformables.sets[set.index as usize].0.clone();
        let (h, n) = self
            .deformables
            .prescribed
            .add_in_box(&self.nodes, set, &label, center, size, true, params)?;
        if n == 0 {
            return Err(StarkError::InvalidInput(format!(
                "the box at {center:?} of size {size:?} contains no node of '{label}'"
            )));
        }
        Ok(h)
    }
}
