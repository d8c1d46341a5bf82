//! Where a new surface can be placed: its clearance above the contact surfaces.

use super::Contact;
use nalgebra::Vector3;

impl Contact {
    /// How far a new surface (vertices `p` and `triangles` indexing them, m) can move straight
    /// down (−z) before it touches the contact surfaces at positions `x`: the smallest vertical
    /// distance from one of its vertices down to a contact triangle, or from a contact point up
    /// to one of its triangles. `None`: nothing below it. Used to place spawned objects at rest
    /// just above what they will land on.
    pub fn clearance_below(&self, x: &[Vector3<f64>], p: &[Vector3<f64>], triangles: &[[usize; 3]]) -> Option<f64> {
        // The height of triangle `t` above the vertical line through `q`, if the line meets it.
        fn height_at(t: [&Vector3<f64>; 3], q: &Vector3<f64>) -> Option<f64> {
            let (a, b, c) = (t[0], t[1], t[2]);
            let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
            if det.abs() < 1e-30 {
                return None;
            }
            let u = ((q.x - a.x) * (c.y - a.y) - (c.x - a.x) * (q.y - a.y)) / det;
            let v = ((b.x - a.x) * (q.y - a.y) - (q.x - a.x) * (b.y - a.y)) / det;
            (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| a.z + u * (b.z - a.z) + v * (c.z - a.z))
        }
        let mut best = f64::INFINITY;
        for t in &self.triangles {
            let tri = [&x[t[0] as usize], &x[t[1] as usize], &x[t[2] as usize]];
            for q in p {
                if let Some(z) = height_at(tri, q) {
                    if z <= q.z {
                        best = best.min(q.z - z);
                    }
                }
            }
        }
        for t in triangles {
            let tri = [&p[t[0]], &p[t[1]], &p[t[2]]];
            for &i in &self.points {
                let s = &x[i as usize];
                if let Some(z) = height_at(tri, s) {
                    if z >= s.z {
                        best = best.min(z - s.z);
                    }
                }
            }
        }
        best.is_finite().then_some(best)
    }
}
