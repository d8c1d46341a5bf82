//! Closed, outward-oriented triangle meshes for rigid bodies: box, icosphere, cylinder, torus and
//! capsule.

use std::collections::HashMap;
use std::f64::consts::PI;

use nalgebra::Vector3;

use super::Mesh;

/// Closed box of full side lengths `size`, centred at the origin: 8 vertices, 12 triangles.
///
/// Reproduces the par_shapes cube (`par_shapes_create_cube`) as used by Stark's `make_box`
/// (moved by −½ and scaled by `size`): vertices `(0,0,0) (0,1,0) (1,1,0) (1,0,0) (0,0,1)
/// (0,1,1) (1,1,1) (1,0,1)` (unit-cube corners, before centring), quads
/// `[7,6,5,4] [0,1,2,3] [6,7,3,2] [5,6,2,1] [4,5,1,0] [7,4,0,3]` each split into
/// `[q0,q1,q2], [q2,q3,q0]`. Outward oriented.
pub fn box_mesh(size: Vector3<f64>) -> Mesh<3> {
    const CORNERS: [[f64; 3]; 8] = [
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
        [1.0, 1.0, 1.0],
        [1.0, 0.0, 1.0],
    ];
    const QUADS: [[usize; 4]; 6] = [
        [7, 6, 5, 4],
        [0, 1, 2, 3],
        [6, 7, 3, 2],
        [5, 6, 2, 1],
        [4, 5, 1, 0],
        [7, 4, 0, 3],
    ];
    let vertices = CORNERS
        .iter()
        .map(|c| (Vector3::from(*c) - Vector3::repeat(0.5)).component_mul(&size))
        .collect();
    let elements = QUADS
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[2], q[3], q[0]]])
        .collect();
    Mesh { vertices, elements }
}

/// Icosphere of the given `radius` centred at the origin, with all vertices on the sphere.
///
/// Starts from a regular icosahedron (12 vertices, 20 triangles) and splits every triangle
/// into four `subdivisions` times, projecting new vertices onto the sphere: `10·4ˢ + 2`
/// vertices and `20·4ˢ` triangles, the same counts as Stark's `make_sphere`
/// (`par_shapes_create_subdivided_sphere`; default `subdivisions = 2`: 162 vertices,
/// 320 triangles). Vertex order differs from par_shapes. Outward oriented.
pub fn sphere_mesh(radius: f64, subdivisions: usize) -> Mesh<3> {
    let phi = 0.5 * (1.0 + 5f64.sqrt());
    let raw: [[f64; 3]; 12] = [
        [-1.0, phi, 0.0],
        [1.0, phi, 0.0],
        [-1.0, -phi, 0.0],
        [1.0, -phi, 0.0],
        [0.0, -1.0, phi],
        [0.0, 1.0, phi],
        [0.0, -1.0, -phi],
        [0.0, 1.0, -phi],
        [phi, 0.0, -1.0],
        [phi, 0.0, 1.0],
        [-phi, 0.0, -1.0],
        [-phi, 0.0, 1.0],
    ];
    let mut unit: Vec<Vector3<f64>> = raw.iter().map(|p| Vector3::from(*p).normalize()).collect();
    let mut triangles: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];

    for _ in 0..subdivisions {
        let mut midpoints: HashMap<[usize; 2], usize> = HashMap::new();
        let mut midpoint = |a: usize, b: usize, unit: &mut Vec<Vector3<f64>>| {
            let key = [a.min(b), a.max(b)];
            *midpoints.entry(key).or_insert_with(|| {
                unit.push((unit[a] + unit[b]).normalize());
                unit.len() - 1
            })
        };
        let mut refined = Vec::with_capacity(4 * triangles.len());
        for &[a, b, c] in &triangles {
            let ab = midpoint(a, b, &mut unit);
            let bc = midpoint(b, c, &mut unit);
            let ca = midpoint(c, a, &mut unit);
            refined.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = refined;
    }

    Mesh {
        vertices: unit.into_iter().map(|p| radius * p).collect(),
        elements: triangles,
    }
}

/// Closed cylinder around the z axis, centred at the origin (z from `−height/2` to
/// `height/2`), with flat caps.
///
/// `slices` vertices around each of the `stacks + 1` rings, then the bottom and the top cap
/// centres: `slices·(stacks+1) + 2` vertices and `2·slices·stacks + 2·slices` triangles, the
/// same counts as Stark's `make_cylinder` (par_shapes cylinder plus two disks, welded;
/// defaults `slices = 16`, `stacks = 1`). Ring vertex `(j, i)` (ring j from the bottom, angle
/// `θᵢ = 2πi/slices` from +x towards +y) has index `slices·j + i`. Unlike Stark's mesh, whose
/// two par_shapes disks both face +z, both caps here face outward.
///
/// # Panics
/// If `slices < 3` or `stacks == 0`.
pub fn cylinder_mesh(radius: f64, height: f64, slices: usize, stacks: usize) -> Mesh<3> {
    assert!(
        slices >= 3 && stacks > 0,
        "cylinder_mesh: need slices >= 3 and stacks >= 1, got {slices} and {stacks}"
    );
    let mut vertices = Vec::with_capacity(slices * (stacks + 1) + 2);
    for j in 0..=stacks {
        let z = -0.5 * height + height * (j as f64 / stacks as f64);
        for i in 0..slices {
            let (s, c) = (2.0 * PI * i as f64 / slices as f64).sin_cos();
            vertices.push(Vector3::new(radius * c, radius * s, z));
        }
    }
    let bottom_center = vertices.len();
    vertices.push(Vector3::new(0.0, 0.0, -0.5 * height));
    let top_center = vertices.len();
    vertices.push(Vector3::new(0.0, 0.0, 0.5 * height));

    let ring = |j: usize, i: usize| slices * j + i % slices;
    let mut elements = Vec::with_capacity(2 * slices * stacks + 2 * slices);
    for j in 0..stacks {
        for i in 0..slices {
            let (a, b, c, d) = (ring(j, i), ring(j, i + 1), ring(j + 1, i + 1), ring(j + 1, i));
            elements.push([a, b, c]);
            elements.push([a, c, d]);
        }
    }
    for i in 0..slices {
        elements.push([bottom_center, ring(0, i + 1), ring(0, i)]);
    }
    for i in 0..slices {
        elements.push([top_center, ring(stacks, i), ring(stacks, i + 1)]);
    }
    Mesh { vertices, elements }
}

/// Closed torus around the z axis, centred at the origin.
///
/// `major_segments` rings around the z axis, each with `minor_segments` vertices around the
/// tube: vertex `(i, j)` has index `minor_segments·i + j` and position
/// `((R + r cos φⱼ) cos θᵢ, (R + r cos φⱼ) sin θᵢ, r sin φⱼ)` with `θᵢ = 2πi/major_segments`,
/// `φⱼ = 2πj/minor_segments`. `major·minor` vertices and `2·major·minor` triangles, seamless
/// and outward oriented. Stark's `make_torus(outer, inner, slices, stacks)` uses par_shapes
/// with `stacks` around the z axis and `slices` around the tube, welded afterwards; the
/// counts agree with `major_radius = outer`, `minor_radius = inner`,
/// `major_segments = stacks`, `minor_segments = slices` (the rigid-body preset `add_torus`
/// defaults to `slices = 16`, `stacks = 32`).
///
/// # Panics
/// If either segment count is below 3.
pub fn torus_mesh(major_radius: f64, minor_radius: f64, major_segments: usize, minor_segments: usize) -> Mesh<3> {
    assert!(
        major_segments >= 3 && minor_segments >= 3,
        "torus_mesh: need at least 3 segments each way, got {major_segments} and {minor_segments}"
    );
    let mut vertices = Vec::with_capacity(major_segments * minor_segments);
    for i in 0..major_segments {
        let (st, ct) = (2.0 * PI * i as f64 / major_segments as f64).sin_cos();
        for j in 0..minor_segments {
            let (sp, cp) = (2.0 * PI * j as f64 / minor_segments as f64).sin_cos();
            let rho = major_radius + minor_radius * cp;
            vertices.push(Vector3::new(rho * ct, rho * st, minor_radius * sp));
        }
    }
    let idx = |i: usize, j: usize| minor_segments * (i % major_segments) + j % minor_segments;
    let mut elements = Vec::with_capacity(2 * major_segments * minor_segments);
    for i in 0..major_segments {
        for j in 0..minor_segments {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            elements.push([a, b, c]);
            elements.push([a, c, d]);
        }
    }
    Mesh { vertices, elements }
}

/// Closed capsule along z, centred: a cylinder of `height` between the centres of two
/// hemispherical caps of `radius`, `slices` vertices around each ring and `cap_rings` rings per
/// cap from the pole to the equator (2·cap_rings rings plus two poles; outward oriented).
///
/// # Panics
/// If `slices < 3` or `cap_rings == 0`.
pub fn capsule_mesh(radius: f64, height: f64, slices: usize, cap_rings: usize) -> Mesh<3> {
    assert!(
        slices >= 3 && cap_rings > 0,
        "capsule_mesh: need slices >= 3 and cap_rings >= 1, got {slices} and {cap_rings}"
    );
    // Rings from the bottom up: (z, ring radius), at the polar angle α from the nearer pole.
    let mut rings = Vec::with_capacity(2 * cap_rings);
    for k in 1..=cap_rings {
        let (s, c) = (0.5 * PI * k as f64 / cap_rings as f64).sin_cos();
        rings.push((-0.5 * height - radius * c, radius * s));
    }
    for k in (1..=cap_rings).rev() {
        let (s, c) = (0.5 * PI * k as f64 / cap_rings as f64).sin_cos();
        rings.push((0.5 * height + radius * c, radius * s));
    }
    let mut vertices = Vec::with_capacity(slices * rings.len() + 2);
    for &(z, rho) in &rings {
        for i in 0..slices {
            let (s, c) = (2.0 * PI * i as f64 / slices as f64).sin_cos();
            vertices.push(Vector3::new(rho * c, rho * s, z));
        }
    }
    let bottom = vertices.len();
    vertices.push(Vector3::new(0.0, 0.0, -0.5 * height - radius));
    let top = vertices.len();
    vertices.push(Vector3::new(0.0, 0.0, 0.5 * height + radius));
    let ring = |j: usize, i: usize| slices * j + i % slices;
    let last = rings.len() - 1;
    let mut elements = Vec::with_capacity(2 * slices * rings.len());
    for j in 0..last {
        for i in 0..slices {
            let (a, b, c, d) = (ring(j, i), ring(j, i + 1), ring(j + 1, i + 1), ring(j + 1, i));
            elements.push([a, b, c]);
            elements.push([a, c, d]);
        }
    }
    for i in 0..slices {
        elements.push([bottom, ring(0, i + 1), ring(0, i)]);
        elements.push([top, ring(last, i), ring(last, i + 1)]);
    }
    Mesh { vertices, elements }
}
