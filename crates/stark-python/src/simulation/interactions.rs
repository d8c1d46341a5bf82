//! Attachments between deformable objects, and contact.

use super::{check_label, report_out, Simulation};
use crate::convert::{Elements, Floats, Indices, Points};
use crate::handles::*;
use crate::params::{self, attachment_params_arg};
use pyo3::prelude::*;

#[pymethods]
impl Simulation {
    /// Glue node `points_a[i]` of `a` to node `points_b[i]` of `b`.
    #[pyo3(signature = (label, a, points_a, b, points_b, params=None))]
    fn add_attachment_point_point(
        &self,
        py: Python<'_>,
        label: &str,
        a: NodesArg,
        points_a: Indices,
        b: NodesArg,
        points_b: Indices,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<AttachmentHandle> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        check_label(label)?;
        let p = attachment_params_arg(py, params)?;
        let h = self.with(|s| {
            s.deformables
                .attachments
                .add_point_point(label, a.0.rust(), &points_a.0, b.0.rust(), &points_b.0, p)
        })?;
        Ok(AttachmentHandle {
            handle: h,
            sim: self.id,
        })
    }

    /// Glue node `points[i]` of `a` to the point `(1 − t) e0 + t e1` of edge `edges[i]` of `b`
    /// with `t = edge_parameters[i]`.
    #[pyo3(signature = (label, a, points, b, edges, edge_parameters, params=None))]
    fn add_attachment_point_edge(
        &self,
        py: Python<'_>,
        label: &str,
        a: NodesArg,
        points: Indices,
        b: NodesArg,
        edges: Elements<2>,
        edge_parameters: Floats,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<AttachmentHandle> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        check_label(label)?;
        let p = attachment_params_arg(py, params)?;
        let h = self.with(|s| {
            s.deformables.attachments.add_point_edge(
                label,
                a.0.rust(),
                &points.0,
                b.0.rust(),
                &edges.0,
                &edge_parameters.0,
                p,
            )
        })?;
        Ok(AttachmentHandle {
            handle: h,
            sim: self.id,
        })
    }

    /// Glue node `points[i]` of `a` to the point with barycentric coordinates `barycentric[i]`
    /// (summing to 1) of triangle `triangles[i]` of `b`.
    #[pyo3(signature = (label, a, points, b, triangles, barycentric, params=None))]
    fn add_attachment_point_triangle(
        &self,
        py: Python<'_>,
        label: &str,
        a: NodesArg,
        points: Indices,
        b: NodesArg,
        triangles: Elements<3>,
        barycentric: Points,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<AttachmentHandle> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        check_label(label)?;
        let p = attachment_params_arg(py, params)?;
        let w: Vec<[f64; 3]> = barycentric.0.iter().map(|v| [v.x, v.y, v.z]).collect();
        let h = self.with(|s| {
            s.deformables
                .attachments
                .add_point_triangle(label, a.0.rust(), &points.0, b.0.rust(), &triangles.0, &w, p)
        })?;
        Ok(AttachmentHandle {
            handle: h,
            sim: self.id,
        })
    }

    /// Largest gap of an attachment group at the current positions, m.
    fn attachment_gap(&self, attachment: AttachmentHandle) -> PyResult<f64> {
        self.own(&attachment)?;
        self.with(|s| s.deformables.attachments.max_gap_m(attachment.handle, &s.nodes.x))
    }

    // -----------------------------------------------------------------------------------------
    // Contact
    // -----------------------------------------------------------------------------------------

    /// All contact objects, in creation order.
    fn contact_objects(&self) -> PyResult<Vec<ContactHandle>> {
        let n = self.get(|s| s.contact.objects().len())?;
        Ok((0..n as u32)
            .map(|i| ContactHandle::new(self.id, stark::contact::ContactHandle(i)))
            .collect())
    }

    /// The contact object labelled `label`, or None.
    fn contact_object(&self, label: &str) -> PyResult<Option<ContactHandle>> {
        Ok(self
            .get(|s| s.contact.object_by_label(label))?
            .map(|h| ContactHandle::new(self.id, h)))
    }

    /// Label of a contact object.
    fn contact_label(&self, contact: ContactArg) -> PyResult<String> {
        self.own(&contact.0)?;
        self.with(|s| {
            s.contact
                .objects()
                .get(contact.0.index as usize)
                .map(|o| o.label.clone())
                .ok_or_else(|| stark::StarkError::InvalidInput("no such contact object".into()))
        })
    }

    /// Contact thickness of an object, m.
    fn contact_thickness(&self, contact: ContactArg) -> PyResult<f64> {
        self.own(&contact.0)?;
        self.with(|s| {
            s.contact
                .objects()
                .get(contact.0.index as usize)
                .map(|o| o.thickness_m)
                .ok_or_else(|| stark::StarkError::InvalidInput("no such contact object".into()))
        })
    }

    /// Change an object's contact thickness, m (a pair activates within the sum of thicknesses).
    fn set_contact_thickness(&self, contact: ContactArg, thickness_m: f64) -> PyResult<()> {
        self.own(&contact.0)?;
        self.with(|s| s.contact.set_thickness(contact.0.rust(), thickness_m))
    }

    /// Friction coefficient μ between two objects (`a` = `b`: self-friction); unset pairs have 0.
    fn set_friction(&self, a: ContactArg, b: ContactArg, mu: f64) -> PyResult<()> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        self.with(|s| s.contact.set_friction(a.0.rust(), b.0.rust(), mu))
    }

    /// Friction coefficient between two objects.
    fn friction(&self, a: ContactArg, b: ContactArg) -> PyResult<f64> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        self.with(|s| s.contact.friction(a.0.rust(), b.0.rust()))
    }

    /// Switch collisions between two objects (`a` = `b`: self-collision) on or off.
    fn set_collision(&self, a: ContactArg, b: ContactArg, enabled: bool) -> PyResult<()> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        self.with(|s| s.contact.set_collision(a.0.rust(), b.0.rust(), enabled))
    }

    /// Switch collisions between two objects off (the original's disable_collision).
    fn disable_collision(&self, a: ContactArg, b: ContactArg) -> PyResult<()> {
        self.set_collision(a, b, false)
    }

    /// Current barrier stiffness κ, N/m (0 before the first step).
    #[getter]
    fn contact_stiffness(&self) -> PyResult<f64> {
        self.get(|s| s.contact.stiffness())
    }

    /// Contact statistics of the last step (active pairs, smallest distance, κ, CCD) as a dict.
    fn contact_stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let stats = self.get(|s| s.contact.stats)?;
        report_out(py, &stats)
    }

    /// Descriptions of all intersecting edge–triangle pairs of the contact surfaces now (exact test).
    fn find_intersections(&self) -> PyResult<Vec<String>> {
        self.get(|s| s.contact.find_intersections(&s.nodes.x))
    }
}
