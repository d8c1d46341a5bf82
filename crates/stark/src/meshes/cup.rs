//! [`cup_mesh`]: the open thin-shell cup (flat bottom, tapered wall, rolled lip) and its
//! parameters [`CupShape`].

use std::f64::consts::PI;

use nalgebra::Vector3;

use super::Mesh;
use crate::error::{check_param, Result, StarkError};

/// Parameters of [`cup_mesh`]: a thin disposable (PET) cup, open at the top, with a rolled lip.
///
/// The defaults describe a 100 mm tall cup, 54 mm across at the rim and 44 mm at the bottom,
/// with a 1.5 mm lip curled through 270°.
#[derive(Clone, Debug, PartialEq)]
pub struct CupShape {
    /// Height of the wall from the bottom (z = 0) to the rim, where the lip starts, m.
    pub height_m: f64,
    /// Radius of the wall at the rim (z = `height_m`), m.
    pub rim_radius_m: f64,
    /// Radius of the flat bottom (z = 0), m; at most `rim_radius_m`.
    pub bottom_radius_m: f64,
    /// Radius of the rolled lip's circular arc, m; at most a quarter of `rim_radius_m` and of
    /// `height_m`.
    pub lip_radius_m: f64,
    /// Angle the lip curls through, in (0°, 300°]: 180° ends pointing down outside the wall,
    /// 270° ends pointing back towards the wall under the curl.
    pub lip_angle_deg: f64,
    /// Vertices around the wall (at least 8). The wall's rows are spaced to make near-equilateral
    /// triangles of edge `2π·r/segments`, and the bottom's rings match that size.
    pub segments: usize,
    /// Largest arc angle one row of the lip may span, in [5°, 180°] (default 45°, so a 270° lip
    /// gets at least 6 rows). Where this makes the lip's rows shorter than the wall's edges, the
    /// lip gets more vertices around than the wall, and the rings at the top of the wall grade
    /// the vertex count up from `segments` to the lip's (by at most 1.5× per row); the lip's
    /// rings get at most 8 times the rim's vertex density. Set it to 180° to give the lip the
    /// wall's vertices around and rows as long as the wall's edges instead (at the defaults
    /// otherwise: 2 rows of 135° for the lip, 2065 vertices instead of 2958).
    pub lip_max_row_angle_deg: f64,
}

impl Default for CupShape {
    fn default() -> Self {
        Self {
            height_m: 0.1,
            rim_radius_m: 0.027,
            bottom_radius_m: 0.022,
            lip_radius_m: 0.0015,
            lip_angle_deg: 270.0,
            segments: 48,
            lip_max_row_angle_deg: 45.0,
        }
    }
}

impl CupShape {
    /// Overall height of the cup, m: the top of the lip's arc,
    /// `height_m + lip_radius_m·(1 − sin τ)` with the wall's taper `sin τ = (rim − bottom radius)
    /// / wall length`, once the lip curls far enough to pass its top (`lip_angle_deg ≥ 90° − τ`;
    /// otherwise the lip's end). About `height_m + lip_radius_m`; 0.101425 m at the defaults.
    /// The mesh's vertices may lie slightly lower (the arc's top need not be a vertex).
    pub fn overall_height_m(&self) -> f64 {
        let tau = self.taper_rad();
        let phi_l = self.lip_angle_deg.to_radians();
        if phi_l >= 0.5 * PI - tau {
            self.height_m + self.lip_radius_m * (1.0 - tau.sin())
        } else {
            self.lip_point(phi_l)[1]
        }
    }

    /// Angle τ of the wall from the vertical (positive when the cup widens upwards).
    fn taper_rad(&self) -> f64 {
        (self.rim_radius_m - self.bottom_radius_m).atan2(self.height_m)
    }

    /// Point `[r, z]` of the lip's profile at the arc angle `phi` (rad) from the rim: the circle
    /// of radius `lip_radius_m` tangent to the wall at the rim, centred on the wall's outer side,
    /// run through clockwise in the (r, z) half-plane (up, then outwards, then down).
    pub(super) fn lip_point(&self, phi: f64) -> [f64; 2] {
        let rho = self.lip_radius_m;
        let tau = self.taper_rad();
        let (st, ct) = tau.sin_cos();
        let center = [self.rim_radius_m + rho * ct, self.height_m - rho * st];
        // Direction of the tangent: the wall's (sin τ, cos τ) rotated clockwise by phi.
        let alpha = 0.5 * PI - tau - phi;
        [center[0] - rho * alpha.sin(), center[1] + rho * alpha.cos()]
    }
}

/// Indices and angular layout of one ring of a surface of revolution: vertex `i` of the ring is
/// `start + i` and sits at the azimuth `2π·(i + offset)/n`.
#[derive(Clone, Copy)]
struct RevolutionRing {
    start: usize,
    n: usize,
    offset: f64,
}

impl RevolutionRing {
    fn index(&self, i: i64) -> usize {
        self.start + i.rem_euclid(self.n as i64) as usize
    }
}

/// Triangulates the band between two rings of a surface of revolution, `a` before `b` along the
/// profile, by advancing around both rings at once and always closing the next triangle with
/// the shorter of the two candidate diagonals. Triangles are `(a_i, a_{i+1}, b_j)` and
/// `(a_i, b_{j+1}, b_j)`: their normal is `e_θ × (profile tangent)`.
fn stitch_rings(vertices: &[Vector3<f64>], a: RevolutionRing, b: RevolutionRing, out: &mut Vec<[usize; 3]>) {
    // Start from the vertex of `b` at or just before a_0 in azimuth.
    let (na, nb) = (a.n as i64, b.n as i64);
    let j0 = ((a.offset / a.n as f64 - b.offset / b.n as f64) * b.n as f64).floor() as i64;
    let (mut i, mut j) = (0i64, j0);
    while i < na || j < j0 + nb {
        let advance_a = if i == na {
            false
        } else if j == j0 + nb {
            true
        } else {
            let d_a = (vertices[a.index(i + 1)] - vertices[b.index(j)]).norm_squared();
            let d_b = (vertices[a.index(i)] - vertices[b.index(j + 1)]).norm_squared();
            d_a <= d_b
        };
        if advance_a {
            out.push([a.index(i), a.index(i + 1), b.index(j)]);
            i += 1;
        } else {
            out.push([a.index(i), b.index(j + 1), b.index(j)]);
            j += 1;
        }
    }
}

/// Thin shell of a disposable plastic cup around the z axis: a flat bottom disk at z = 0, a
/// tapered wall (a cone frustum from `bottom_radius_m` at z = 0 to `rim_radius_m` at
/// z = `height_m`) and a rolled lip.
///
/// The lip continues the wall from the rim as a circular arc of radius `lip_radius_m` in the
/// (r, z) half-plane, tangent to the wall at the rim and curling outwards over the top and down
/// through `lip_angle_deg` (see [`CupShape::lip_angle_deg`]). The top of the arc is at
/// z = `height_m + lip_radius_m·(1 − sin τ)` ≈ `height_m + lip_radius_m` (τ the wall's taper
/// from the vertical; see [`CupShape::overall_height_m`]), so the overall height is about
/// `height_m + lip_radius_m` and the lip reaches out to a radius of about
/// `rim_radius_m + 2·lip_radius_m`.
///
/// The mesh is one connected, manifold, consistently oriented triangle surface with shared
/// vertices; the lip's free edge (the last ring) is its only boundary loop. Normals point out of
/// the cup: away from the axis on the wall, −z on the bottom, and — continuing the wall's outer
/// side around the curl — towards the lip's arc centre on the lip. Vertices lie on the analytic
/// surface, in rings: vertex 0 is the bottom's centre, then the rings in order along the
/// profile (bottom rings outwards, wall rings upwards, lip rings along the curl), each ring
/// counter-clockwise seen from +z, consecutive rings staggered by half a spacing.
///
/// Sizes: the wall has `segments` vertices around and rows spaced so its triangles are close to
/// equilateral; the bottom has concentric rings, spaced like the wall's rows, whose vertex
/// counts fall towards a centre fan of about 5 triangles; the lip is refined as described at
/// [`CupShape::lip_max_row_angle_deg`]. At the defaults: 2958 vertices, 5782 triangles, edges
/// from 1.29 mm (lip) to 3.97 mm (wall), smallest angle 38°.
///
/// # Errors
/// [`StarkError::InvalidParameter`] naming the field if a size is not positive and finite,
/// `bottom_radius_m > rim_radius_m`, the lip is too large (`lip_radius_m` above a quarter of
/// `rim_radius_m` or of `height_m`), `lip_angle_deg` is outside (0°, 300°],
/// `lip_max_row_angle_deg` outside [5°, 180°] or `segments < 8`; and
/// [`StarkError::InvalidInput`] if the finished mesh intersects itself (a final exact check of
/// every edge against every triangle not sharing a vertex with it; a safeguard — no accepted
/// parameters are known to trigger it).
pub fn cup_mesh(shape: &CupShape) -> Result<Mesh<3>> {
    const OBJECT: &str = "cup_mesh";
    let positive = |v: f64| v > 0.0 && v.is_finite();
    for (field, value) in [
        ("height_m", shape.height_m),
        ("rim_radius_m", shape.rim_radius_m),
        ("bottom_radius_m", shape.bottom_radius_m),
    ] {
        check_param(OBJECT, field, value, positive(value), "must be positive and finite")?;
    }
    check_param(
        OBJECT,
        "bottom_radius_m",
        shape.bottom_radius_m,
        shape.bottom_radius_m <= shape.rim_radius_m,
        "must not exceed rim_radius_m",
    )?;
    check_param(
        OBJECT,
        "lip_radius_m",
        shape.lip_radius_m,
        positive(shape.lip_radius_m),
        "must be positive and finite",
    )?;
    check_param(
        OBJECT,
        "lip_radius_m",
        shape.lip_radius_m,
        shape.lip_radius_m <= 0.25 * shape.rim_radius_m.min(shape.height_m),
        "is too large: must be at most a quarter of rim_radius_m and of height_m",
    )?;
    check_param(
        OBJECT,
        "lip_angle_deg",
        shape.lip_angle_deg,
        shape.lip_angle_deg > 0.0 && shape.lip_angle_deg <= 300.0,
        "must lie in (0, 300]",
    )?;
    check_param(
        OBJECT,
        "lip_max_row_angle_deg",
        shape.lip_max_row_angle_deg,
        (5.0..=180.0).contains(&shape.lip_max_row_angle_deg),
        "must lie in [5, 180]",
    )?;
    check_param(
        OBJECT,
        "segments",
        shape.segments as f64,
        shape.segments >= 8,
        "must be at least 8",
    )?;

    let n_wall = shape.segments;
    let (r_bottom, r_rim, height) = (shape.bottom_radius_m, shape.rim_radius_m, shape.height_m);
    let wall_length = (r_rim - r_bottom).hypot(height);
    // Staggered rings a distance `row` apart with spacing `h` around make near-equilateral
    // triangles when row = h·√3/2.
    let row_factor = 0.5 * 3f64.sqrt();
    let spacing = |r: f64, n: usize| 2.0 * PI * r / n as f64;

    // Lip: rows along the arc, and the vertex count of its rings.
    let phi_lip = shape.lip_angle_deg.to_radians();
    let arc_length = shape.lip_radius_m * phi_lip;
    let h_rim = spacing(r_rim, n_wall);
    let rows_by_size = (arc_length / (row_factor * h_rim)).round() as usize;
    let rows_by_angle = (shape.lip_angle_deg / shape.lip_max_row_angle_deg).ceil() as usize;
    let lip_rows = rows_by_size.max(rows_by_angle).max(1);
    let lip_profile: Vec<[f64; 2]> = (0..=lip_rows)
        .map(|k| shape.lip_point(phi_lip * k as f64 / lip_rows as f64))
        .collect();
    let r_lip_mean = lip_profile.iter().map(|p| p[0]).sum::<f64>() / lip_profile.len() as f64;
    let h_lip = (arc_length / lip_rows as f64 / row_factor).max(h_rim / 8.0);
    let n_lip = ((2.0 * PI * r_lip_mean / h_lip).round() as usize).max(n_wall);

    // Wall: uniform rows of `n_wall` vertices, then (if the lip is finer) rows grading the count
    // up to `n_lip` at the rim, by at most 1.5× per row.
    let grading_rows = if n_lip > n_wall {
        ((n_lip as f64 / n_wall as f64).ln() / 1.5f64.ln()).ceil() as usize
    } else {
        0
    };
    let grading_counts: Vec<usize> = (0..=grading_rows)
        .map(|i| {
            if i == grading_rows {
                n_lip
            } else {
                (n_wall as f64 * (n_lip as f64 / n_wall as f64).powf(i as f64 / grading_rows as f64)).round() as usize
            }
        })
        .collect();
    let grading_steps: Vec<f64> = grading_counts
        .windows(2)
        .map(|w| row_factor * 0.5 * (spacing(r_rim, w[0]) + spacing(r_rim, w[1])))
        .collect();
    let grading_length: f64 = grading_steps.iter().sum();
    let wall_row = row_factor * spacing(0.5 * (r_bottom + r_rim), n_wall);
    let uniform_rows = (((wall_length - grading_length) / wall_row).round() as usize).max(1);
    let scale = wall_length / (uniform_rows as f64 * wall_row + grading_length);
    // Rings along the wall as (arc length from the bottom, vertex count).
    let mut wall_rings: Vec<(f64, usize)> = (0..=uniform_rows)
        .map(|j| (j as f64 * wall_row * scale, n_wall))
        .collect();
    let mut s = uniform_rows as f64 * wall_row;
    for (step, &count) in grading_steps.iter().zip(&grading_counts[1..]) {
        s += step;
        wall_rings.push((s * scale, count));
    }
    wall_rings.last_mut().expect("the wall has rings").0 = wall_length;

    // Bottom: concentric rings spaced like the wall's rows, with the wall's spacing around.
    let h_bottom = spacing(r_bottom, n_wall);
    let disk_rings = ((r_bottom / (row_factor * h_bottom)).round() as usize).max(1);

    // All rings along the profile as (r, z, vertex count).
    let mut rings: Vec<(f64, f64, usize)> = Vec::new();
    for k in 1..disk_rings {
        let count = ((n_wall * k) as f64 / disk_rings as f64).round() as usize;
        rings.push((r_bottom * k as f64 / disk_rings as f64, 0.0, count.max(5)));
    }
    for &(s, count) in &wall_rings {
        let t = s / wall_length;
        rings.push((r_bottom + (r_rim - r_bottom) * t, height * t, count));
    }
    for p in &lip_profile[1..] {
        rings.push((p[0], p[1], n_lip));
    }

    let mut vertices = vec![Vector3::zeros()];
    let mut layout = Vec::with_capacity(rings.len());
    for (k, &(r, z, n)) in rings.iter().enumerate() {
        let offset = 0.5 * (k % 2) as f64;
        layout.push(RevolutionRing {
            start: vertices.len(),
            n,
            offset,
        });
        for i in 0..n {
            let (s, c) = (2.0 * PI * (i as f64 + offset) / n as f64).sin_cos();
            vertices.push(Vector3::new(r * c, r * s, z));
        }
    }

    let mut elements = Vec::new();
    let first = layout[0];
    for i in 0..first.n as i64 {
        elements.push([0, first.index(i + 1), first.index(i)]);
    }
    for w in layout.windows(2) {
        stitch_rings(&vertices, w[0], w[1], &mut elements);
    }

    let edges = crate::geometry::edges_from_triangles(&elements);
    let hits =
        crate::geometry::intersection::find_edge_triangle_intersections(&vertices, &edges, &elements, |_, _| true)
            .map_err(|e| StarkError::InvalidInput(format!("{OBJECT}: {e}")))?;
    if let Some(&(e, t)) = hits.first() {
        return Err(StarkError::InvalidInput(format!(
            "{OBJECT}: the surface intersects itself (edge {:?} crosses triangle {:?}, {} such pairs); \
             increase `segments` or lower `lip_angle_deg` or `lip_max_row_angle_deg`",
            edges[e],
            elements[t],
            hits.len()
        )));
    }
    Ok(Mesh { vertices, elements })
}
