//! Mesh generators (ground floor: they use only `error` and `geometry`; `presets::meshes`
//! re-exports them).
//!
//! The grid generators ([`triangle_grid`], [`tet_grid`], [`segment_line`],
//! [`cylindrical_triangle_grid`]) reproduce the vertex order, element order and local vertex
//! order of the C++ Stark generators in `stark/src/utils/mesh_generators.cpp` exactly, and
//! compute vertex positions with the same floating-point expressions, so that benchmark scenes
//! built from them match the original element by element.
//!
//! The closed meshes for rigid bodies ([`box_mesh`], [`sphere_mesh`], [`cylinder_mesh`],
//! [`torus_mesh`]) are watertight and outward oriented (counter-clockwise seen from outside,
//! so the signed volume is positive). [`box_mesh`] reproduces the par_shapes cube used by
//! Stark's `make_box` vertex for vertex; the others have the same vertex and triangle counts
//! as Stark's par_shapes-based shapes but their own (deterministic) ordering.
//!
//! [`cup_mesh`] builds an open thin-shell cup (flat bottom, tapered wall, rolled lip) for
//! simulations of grasping a disposable cup; it checks its parameters and returns an error
//! instead of panicking.
//!
//! Counts of zero (no quads, no segments, fewer than three slices, ...) are programmer errors
//! and panic with a message naming the argument.

use std::collections::HashMap;
use std::f64::consts::PI;

use nalgebra::Vector3;

use crate::error::{check_param, Result, StarkError};

/// A simplicial mesh: vertex positions and `K`-vertex elements indexing into them.
///
/// `K = 2` segments, `K = 3` triangles, `K = 4` tetrahedra. Mirrors Stark's `stark::Mesh<N>`
/// (`stark/src/utils/Mesh.h`), whose `conn` field is called `elements` here.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh<const K: usize> {
    /// Vertex positions in metres.
    pub vertices: Vec<Vector3<f64>>,
    /// Elements as `K` indices into [`Mesh::vertices`].
    pub elements: Vec<[usize; K]>,
}

/// A segment (polyline) mesh.
pub type SegmentMesh = Mesh<2>;
/// A triangle mesh.
pub type TriangleMesh = Mesh<3>;
/// A tetrahedral mesh.
pub type TetMesh = Mesh<4>;

/// Regular grid of `quads[0] × quads[1]` quads in the plane `z`, each split into two triangles.
///
/// Reproduces Stark's `generate_triangle_grid` exactly:
/// - `(quads[0]+1)·(quads[1]+1)` vertices; vertex `(i, j)` (i along x, j along y) has index
///   `(quads[1]+1)·i + j` and position `bottom + (i·dx, j·dy)` with
///   `bottom = center − size/2`, `dx = (top − bottom)/quads` ("move y, then x").
/// - `2·quads[0]·quads[1]` triangles, quads visited with x outer, y inner. With the quad
///   corners `n0 = (i, j)`, `n1 = (i, j+1)`, `n2 = (i+1, j)`, `n3 = (i+1, j+1)`, a quad with
///   `i % 2 == j % 2` yields `[n0, n2, n3], [n0, n3, n1]` and otherwise
///   `[n0, n2, n1], [n2, n3, n1]` (alternating diagonals).
///
/// All triangles are counter-clockwise seen from +z (normal `+z`).
///
/// # Panics
/// If a quad count is zero.
pub fn triangle_grid(center: [f64; 2], size: [f64; 2], quads: [usize; 2], z: f64) -> Mesh<3> {
    assert!(
        quads[0] > 0 && quads[1] > 0,
        "triangle_grid: quads must be positive, got {quads:?}"
    );
    let bottom = [center[0] - 0.5 * size[0], center[1] - 0.5 * size[1]];
    let top = [center[0] + 0.5 * size[0], center[1] + 0.5 * size[1]];
    let nx = quads[0] + 1;
    let ny = quads[1] + 1;
    let dx = (top[0] - bottom[0]) / quads[0] as f64;
    let dy = (top[1] - bottom[1]) / quads[1] as f64;

    let mut vertices = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        for j in 0..ny {
            vertices.push(Vector3::new(bottom[0] + i as f64 * dx, bottom[1] + j as f64 * dy, z));
        }
    }

    let mut elements = Vec::with_capacity(2 * quads[0] * quads[1]);
    for ei in 0..quads[0] {
        for ej in 0..quads[1] {
            let n0 = ny * ei + ej;
            let n1 = ny * ei + ej + 1;
            let n2 = ny * (ei + 1) + ej;
            let n3 = ny * (ei + 1) + ej + 1;
            if ei % 2 == ej % 2 {
                elements.push([n0, n2, n3]);
                elements.push([n0, n3, n1]);
            } else {
                elements.push([n0, n2, n1]);
                elements.push([n2, n3, n1]);
            }
        }
    }
    Mesh { vertices, elements }
}

/// Open cylindrical tube of triangles around the z axis, from `z = 0` to `z = height`.
///
/// Reproduces Stark's `generate_cylindrical_triangle_mesh` exactly: `quads[0]` vertices around
/// the circumference (no duplicate at the seam) times `quads[1] + 1` rings; vertex `(i, j)`
/// (i around, j up) has index `(quads[1]+1)·i + j` and position
/// `(r cos θᵢ, r sin θᵢ, j·dz)`, `θᵢ = i·2π/quads[0]`. Quad `(i, j)` uses
/// `n0 = (i, j)`, `n1 = (i, j+1)`, `n2 = (i+1 mod n, j)`, `n3 = (i+1 mod n, j+1)` and yields
/// `[n0, n2, n3], [n0, n3, n1]` when `(i + j)` is even, else `[n0, n2, n1], [n2, n3, n1]`.
/// Normals point outward (away from the axis).
///
/// # Panics
/// If `quads[0] < 3` or `quads[1] == 0`.
pub fn cylindrical_triangle_grid(radius: f64, height: f64, quads: [usize; 2]) -> Mesh<3> {
    assert!(
        quads[0] >= 3 && quads[1] > 0,
        "cylindrical_triangle_grid: need at least 3 quads around and 1 along the height, got {quads:?}"
    );
    let nx = quads[0];
    let ny = quads[1] + 1;
    let dtheta = 2.0 * PI / quads[0] as f64;
    let dz = height / quads[1] as f64;

    let mut vertices = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        let theta = i as f64 * dtheta;
        let (s, c) = theta.sin_cos();
        for j in 0..ny {
            vertices.push(Vector3::new(radius * c, radius * s, j as f64 * dz));
        }
    }

    let mut elements = Vec::with_capacity(2 * quads[0] * quads[1]);
    for i in 0..quads[0] {
        let ip1 = (i + 1) % nx;
        for j in 0..quads[1] {
            let n0 = i * ny + j;
            let n1 = i * ny + j + 1;
            let n2 = ip1 * ny + j;
            let n3 = ip1 * ny + j + 1;
            if (i + j) % 2 == 0 {
                elements.push([n0, n2, n3]);
                elements.push([n0, n3, n1]);
            } else {
                elements.push([n0, n2, n1]);
                elements.push([n2, n3, n1]);
            }
        }
    }
    Mesh { vertices, elements }
}

/// Local tets of one hex for the "even" checkerboard colour, in Stark's order (local corner
/// ids 0..8 as in [`tet_grid`], 8 = hex centre).
const HEX_TETS_EVEN: [[usize; 4]; 12] = [
    [0, 1, 4, 8], // front
    [1, 5, 4, 8],
    [0, 2, 1, 8], // left
    [1, 2, 3, 8],
    [0, 4, 6, 8], // bottom
    [0, 6, 2, 8],
    [3, 2, 7, 8], // back
    [2, 6, 7, 8],
    [4, 5, 7, 8], // right
    [4, 7, 6, 8],
    [1, 3, 5, 8], // top
    [3, 7, 5, 8],
];

/// Local tets of one hex for the "odd" checkerboard colour, in Stark's order.
const HEX_TETS_ODD: [[usize; 4]; 12] = [
    [0, 1, 5, 8], // front
    [0, 5, 4, 8],
    [0, 3, 1, 8], // left
    [0, 2, 3, 8],
    [0, 4, 2, 8], // bottom
    [2, 4, 6, 8],
    [3, 2, 6, 8], // back
    [3, 6, 7, 8],
    [5, 7, 6, 8], // right
    [5, 6, 4, 8],
    [1, 3, 7, 8], // top
    [1, 7, 5, 8],
];

/// Regular grid of `hexes[0] × hexes[1] × hexes[2]` hexahedra, each split into 12 tetrahedra
/// around an extra vertex at the hex centre.
///
/// Reproduces Stark's `generate_tet_grid` exactly:
/// - First the `(hexes[0]+1)(hexes[1]+1)(hexes[2]+1)` corner vertices; corner `(i, j, k)` has
///   index `nz·ny·i + nz·j + k` (`n* = hexes[*] + 1`, "move z, then y, then x") and position
///   `bottom + (i·dx, j·dy, k·dz)`, `bottom = center − size/2`, `d* = (top − bottom)/hexes`.
/// - Then the `hexes[0]·hexes[1]·hexes[2]` hex-centre vertices; hex `(i, j, k)` has centre
///   index `n_corners + hz·hy·i + hz·j + k` (`h* = hexes[*]`) and position
///   `bottom + i·dx + dx/2` (per axis).
/// - 12 tets per hex, hexes visited x outer, z inner. With the hex corners numbered
///   `c = 4·di + 2·dj + dk` (`d* ∈ {0, 1}`) and the centre as 8, hexes where
///   `(k even and i%2 == j%2) or (k odd and i%2 != j%2)` use
///   `[0,1,4,8] [1,5,4,8] [0,2,1,8] [1,2,3,8] [0,4,6,8] [0,6,2,8] [3,2,7,8] [2,6,7,8]
///   [4,5,7,8] [4,7,6,8] [1,3,5,8] [3,7,5,8]` and the others
///   `[0,1,5,8] [0,5,4,8] [0,3,1,8] [0,2,3,8] [0,4,2,8] [2,4,6,8] [3,2,6,8] [3,6,7,8]
///   [5,7,6,8] [5,6,4,8] [1,3,7,8] [1,7,5,8]` (checkerboard alternation of the face
///   diagonals, so neighbouring hexes share conforming faces).
///
/// Every tet of Stark's ordering has positive signed volume
/// `((x1−x0)×(x2−x0))·(x3−x0)/6 > 0` (checked in the tests), so no reordering is needed.
///
/// # Panics
/// If a hex count is zero.
pub fn tet_grid(center: Vector3<f64>, size: Vector3<f64>, hexes: [usize; 3]) -> Mesh<4> {
    assert!(
        hexes.iter().all(|&n| n > 0),
        "tet_grid: hexes must be positive, got {hexes:?}"
    );
    let bottom = center - 0.5 * size;
    let top = center + 0.5 * size;
    let [hx, hy, hz] = hexes;
    let (nx, ny, nz) = (hx + 1, hy + 1, hz + 1);
    let n_corners = nx * ny * nz;
    let n_hexes = hx * hy * hz;
    let d = Vector3::new(
        (top[0] - bottom[0]) / hx as f64,
        (top[1] - bottom[1]) / hy as f64,
        (top[2] - bottom[2]) / hz as f64,
    );
    let d_half = 0.5 * d;

    let mut vertices = Vec::with_capacity(n_corners + n_hexes);
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                vertices.push(Vector3::new(
                    bottom[0] + i as f64 * d[0],
                    bottom[1] + j as f64 * d[1],
                    bottom[2] + k as f64 * d[2],
                ));
            }
        }
    }
    for i in 0..hx {
        for j in 0..hy {
            for k in 0..hz {
                vertices.push(Vector3::new(
                    bottom[0] + i as f64 * d[0] + d_half[0],
                    bottom[1] + j as f64 * d[1] + d_half[1],
                    bottom[2] + k as f64 * d[2] + d_half[2],
                ));
            }
        }
    }

    let mut elements = Vec::with_capacity(12 * n_hexes);
    for ei in 0..hx {
        for ej in 0..hy {
            for ek in 0..hz {
                let corner = |di: usize, dj: usize, dk: usize| nz * ny * (ei + di) + nz * (ej + dj) + (ek + dk);
                let nodes = [
                    corner(0, 0, 0),
                    corner(0, 0, 1),
                    corner(0, 1, 0),
                    corner(0, 1, 1),
                    corner(1, 0, 0),
                    corner(1, 0, 1),
                    corner(1, 1, 0),
                    corner(1, 1, 1),
                    n_corners + hz * hy * ei + hz * ej + ek,
                ];
                let even = (ek % 2 == 0 && ei % 2 == ej % 2) || (ek % 2 == 1 && ei % 2 != ej % 2);
                let local = if even { &HEX_TETS_EVEN } else { &HEX_TETS_ODD };
                elements.extend(local.iter().map(|t| t.map(|c| nodes[c])));
            }
        }
    }
    Mesh { vertices, elements }
}

/// Straight polyline from `begin` to `end` with `n_segments` equal segments.
///
/// Reproduces Stark's `generate_segment_line`: vertex `i` is
/// `begin + (end − begin)·(i / n_segments)` and segment `i` is `[i, i + 1]`.
///
/// # Panics
/// If `n_segments` is zero.
pub fn segment_line(begin: Vector3<f64>, end: Vector3<f64>, n_segments: usize) -> Mesh<2> {
    assert!(n_segments > 0, "segment_line: n_segments must be positive");
    let vertices = (0..=n_segments)
        .map(|i| begin + (end - begin) * (i as f64 / n_segments as f64))
        .collect();
    let elements = (0..n_segments).map(|i| [i, i + 1]).collect();
    Mesh { vertices, elements }
}

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
    fn lip_point(&self, phi: f64) -> [f64; 2] {
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn signed_volume(m: &Mesh<3>) -> f64 {
        m.elements
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.vertices[i]);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum()
    }

    fn tet_volume(m: &Mesh<4>, t: &[usize; 4]) -> f64 {
        let [x0, x1, x2, x3] = t.map(|i| m.vertices[i]);
        (x1 - x0).cross(&(x2 - x0)).dot(&(x3 - x0)) / 6.0
    }

    /// Every directed edge appears once and its reverse once: closed, manifold, consistently
    /// oriented.
    fn assert_watertight(m: &Mesh<3>) {
        let mut directed: HashMap<[usize; 2], usize> = HashMap::new();
        for (ti, t) in m.elements.iter().enumerate() {
            assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "triangle {ti} degenerate");
            for k in 0..3 {
                *directed.entry([t[k], t[(k + 1) % 3]]).or_default() += 1;
            }
        }
        for (&[a, b], &n) in &directed {
            assert_eq!(n, 1, "directed edge ({a}, {b}) used {n} times");
            assert_eq!(directed.get(&[b, a]), Some(&1), "edge ({a}, {b}) has no twin");
        }
        let mut used = vec![false; m.vertices.len()];
        m.elements.iter().flatten().for_each(|&i| used[i] = true);
        assert!(used.iter().all(|&u| u), "unused vertex");
    }

    fn euler_characteristic(m: &Mesh<3>) -> i64 {
        let mut edges: Vec<[usize; 2]> = m
            .elements
            .iter()
            .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        m.vertices.len() as i64 - edges.len() as i64 + m.elements.len() as i64
    }

    #[test]
    fn triangle_grid_2x2_matches_stark_ordering() {
        let m = triangle_grid([0.0, 0.0], [2.0, 2.0], [2, 2], 0.5);
        assert_eq!(m.vertices.len(), 9);
        // vertex (i, j) at index 3 i + j: y moves fastest.
        assert_eq!(m.vertices[0], Vector3::new(-1.0, -1.0, 0.5));
        assert_eq!(m.vertices[1], Vector3::new(-1.0, 0.0, 0.5));
        assert_eq!(m.vertices[3], Vector3::new(0.0, -1.0, 0.5));
        assert_eq!(m.vertices[8], Vector3::new(1.0, 1.0, 0.5));
        // Derived by hand from `generate_triangle_grid` (quads: x outer, y inner).
        let expected = vec![
            [0, 3, 4],
            [0, 4, 1], // quad (0,0): even
            [1, 4, 2],
            [4, 5, 2], // quad (0,1): odd
            [3, 6, 4],
            [6, 7, 4], // quad (1,0): odd
            [4, 7, 8],
            [4, 8, 5], // quad (1,1): even
        ];
        assert_eq!(m.elements, expected);
    }

    #[test]
    fn triangle_grid_counts_and_normals() {
        for (nx, ny) in [(1, 1), (3, 5), (32, 32)] {
            let m = triangle_grid([0.3, -0.2], [1.0, 0.5], [nx, ny], 0.0);
            assert_eq!(m.vertices.len(), (nx + 1) * (ny + 1));
            assert_eq!(m.elements.len(), 2 * nx * ny);
            let mut area = 0.0;
            for t in &m.elements {
                let [a, b, c] = t.map(|i| m.vertices[i]);
                let n = (b - a).cross(&(c - a));
                assert!(n.z > 0.0);
                area += 0.5 * n.z;
            }
            assert!((area - 0.5).abs() < 1e-12);
        }
        // Benchmark scene `hanging_cloth`: {32,32} -> 1089 v, 2048 tri.
        let cloth = triangle_grid([0.0, 0.0], [1.0, 1.0], [32, 32], 0.0);
        assert_eq!((cloth.vertices.len(), cloth.elements.len()), (1089, 2048));
    }

    #[test]
    fn tet_grid_2x2x2_matches_stark_ordering() {
        let m = tet_grid(Vector3::zeros(), Vector3::repeat(2.0), [2, 2, 2]);
        assert_eq!(m.vertices.len(), 27 + 8);
        assert_eq!(m.elements.len(), 96);
        // corner (i,j,k) at 9 i + 3 j + k; centre (i,j,k) at 27 + 4 i + 2 j + k.
        assert_eq!(m.vertices[0], Vector3::new(-1.0, -1.0, -1.0));
        assert_eq!(m.vertices[1], Vector3::new(-1.0, -1.0, 0.0));
        assert_eq!(m.vertices[3], Vector3::new(-1.0, 0.0, -1.0));
        assert_eq!(m.vertices[9], Vector3::new(0.0, -1.0, -1.0));
        assert_eq!(m.vertices[27], Vector3::new(-0.5, -0.5, -0.5));
        assert_eq!(m.vertices[28], Vector3::new(-0.5, -0.5, 0.5));
        assert_eq!(m.vertices[34], Vector3::new(0.5, 0.5, 0.5));
        // Hex (0,0,0): corners [0,1,3,4,9,10,12,13], centre 27, "even" pattern.
        let hex0 = [
            [0, 1, 9, 27],
            [1, 10, 9, 27],
            [0, 3, 1, 27],
            [1, 3, 4, 27],
            [0, 9, 12, 27],
            [0, 12, 3, 27],
            [4, 3, 13, 27],
            [3, 12, 13, 27],
            [9, 10, 13, 27],
            [9, 13, 12, 27],
            [1, 4, 10, 27],
            [4, 13, 10, 27],
        ];
        assert_eq!(&m.elements[..12], &hex0);
        // Hex (0,0,1): corners [1,2,4,5,10,11,13,14], centre 28, k odd and i%2 == j%2: "odd".
        let hex1 = [
            [1, 2, 11, 28],
            [1, 11, 10, 28],
            [1, 5, 2, 28],
            [1, 4, 5, 28],
            [1, 10, 4, 28],
            [4, 10, 13, 28],
            [5, 4, 13, 28],
            [5, 13, 14, 28],
            [11, 14, 13, 28],
            [11, 13, 10, 28],
            [2, 5, 14, 28],
            [2, 14, 11, 28],
        ];
        assert_eq!(&m.elements[12..24], &hex1);
        // Hex (0,1,0): corners [3,4,6,7,12,13,15,16], centre 29, k even, i%2 != j%2: "odd".
        assert_eq!(m.elements[24], [3, 4, 13, 29]);
        // Hex (1,1,0): centre 33, even again; first tet [c0, c1, c4, centre].
        assert_eq!(m.elements[6 * 12], [12, 13, 21, 33]);
    }

    #[test]
    fn tet_grid_volumes_positive_and_sum_to_box() {
        let size = Vector3::new(0.5, 0.3, 0.7);
        for hexes in [[1, 1, 1], [2, 3, 4], [5, 5, 5]] {
            let m = tet_grid(Vector3::new(0.1, 0.2, -0.3), size, hexes);
            let n_hex = hexes[0] * hexes[1] * hexes[2];
            let n_corner = (hexes[0] + 1) * (hexes[1] + 1) * (hexes[2] + 1);
            assert_eq!(m.vertices.len(), n_corner + n_hex);
            assert_eq!(m.elements.len(), 12 * n_hex);
            let mut total = 0.0;
            for (i, t) in m.elements.iter().enumerate() {
                let v = tet_volume(&m, t);
                assert!(v > 0.0, "tet {i} has volume {v}");
                total += v;
            }
            let expected = size.x * size.y * size.z;
            assert!(
                (total - expected).abs() < 1e-12 * expected.max(1.0),
                "{total} vs {expected}"
            );
        }
        // Benchmark scenes: {10,10,10} -> 2331 v / 12000 tets; {5,5,5} -> 341/1500; {2,2,2} -> 35/96.
        for (n, nv, nt) in [(10, 2331, 12000), (5, 341, 1500), (2, 35, 96)] {
            let m = tet_grid(Vector3::zeros(), Vector3::repeat(0.5), [n, n, n]);
            assert_eq!((m.vertices.len(), m.elements.len()), (nv, nt));
        }
    }

    #[test]
    fn tet_grid_is_conforming() {
        // Every interior triangle face is shared by exactly two tets with opposite
        // orientation; boundary faces number 2 per boundary quad.
        let hexes = [3, 2, 4];
        let m = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), hexes);
        let mut faces: HashMap<[usize; 3], usize> = HashMap::new();
        for t in &m.elements {
            for f in [
                [t[0], t[1], t[2]],
                [t[0], t[1], t[3]],
                [t[0], t[2], t[3]],
                [t[1], t[2], t[3]],
            ] {
                let mut f = f;
                f.sort_unstable();
                *faces.entry(f).or_default() += 1;
            }
        }
        assert!(faces.values().all(|&c| c == 1 || c == 2));
        let boundary = faces.values().filter(|&&c| c == 1).count();
        let [a, b, c] = hexes;
        assert_eq!(boundary, 4 * (a * b + b * c + a * c));
    }

    #[test]
    fn segment_line_matches_stark() {
        let m = segment_line(Vector3::zeros(), Vector3::new(1.0, 2.0, 0.0), 4);
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(m.elements, vec![[0, 1], [1, 2], [2, 3], [3, 4]]);
        assert_eq!(m.vertices[2], Vector3::new(0.5, 1.0, 0.0));
        assert_eq!(m.vertices[4], Vector3::new(1.0, 2.0, 0.0));
    }

    #[test]
    fn cylindrical_grid_matches_stark() {
        let m = cylindrical_triangle_grid(1.0, 2.0, [4, 2]);
        assert_eq!(m.vertices.len(), 12);
        assert_eq!(m.elements.len(), 16);
        assert_eq!(&m.elements[..4], &[[0, 3, 4], [0, 4, 1], [1, 4, 2], [4, 5, 2]]);
        // Wrap-around quad (i = 3, j = 0): odd.
        assert_eq!(m.elements[12], [9, 0, 10]);
        for t in &m.elements {
            let [a, b, c] = t.map(|i| m.vertices[i]);
            let n = (b - a).cross(&(c - a));
            let mid = (a + b + c) / 3.0;
            assert!(n.dot(&Vector3::new(mid.x, mid.y, 0.0)) > 0.0);
        }
    }

    #[test]
    fn box_is_par_shapes_cube() {
        let m = box_mesh(Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(m.vertices.len(), 8);
        assert_eq!(m.elements.len(), 12);
        assert_eq!(m.vertices[1], Vector3::new(-0.5, 1.0, -1.5));
        assert_eq!(m.vertices[7], Vector3::new(0.5, -1.0, 1.5));
        assert_eq!(&m.elements[..2], &[[7, 6, 5], [5, 4, 7]]);
        assert_watertight(&m);
        assert_eq!(euler_characteristic(&m), 2);
        assert!((signed_volume(&m) - 6.0).abs() < 1e-12);
    }

    #[test]
    fn sphere_is_closed_and_close_to_analytic() {
        for s in 0..=4 {
            let m = sphere_mesh(0.7, s);
            assert_eq!(m.vertices.len(), 10 * 4usize.pow(s as u32) + 2);
            assert_eq!(m.elements.len(), 20 * 4usize.pow(s as u32));
            assert_watertight(&m);
            assert_eq!(euler_characteristic(&m), 2);
            assert!(m.vertices.iter().all(|v| (v.norm() - 0.7).abs() < 1e-12));
            let v = signed_volume(&m);
            let exact = 4.0 / 3.0 * PI * 0.7f64.powi(3);
            assert!(v > 0.0 && v < exact);
            if s >= 3 {
                assert!((exact - v) / exact < 0.01, "s = {s}: {v} vs {exact}");
            }
        }
    }

    #[test]
    fn cylinder_is_closed_with_polygonal_prism_volume() {
        for (slices, stacks) in [(3, 1), (16, 1), (64, 5)] {
            let (r, h) = (0.3, 1.2);
            let m = cylinder_mesh(r, h, slices, stacks);
            assert_eq!(m.vertices.len(), slices * (stacks + 1) + 2);
            assert_eq!(m.elements.len(), 2 * slices * stacks + 2 * slices);
            assert_watertight(&m);
            assert_eq!(euler_characteristic(&m), 2);
            let prism = 0.5 * slices as f64 * r * r * (2.0 * PI / slices as f64).sin() * h;
            assert!((signed_volume(&m) - prism).abs() < 1e-12);
            if slices == 64 {
                let exact = PI * r * r * h;
                assert!((exact - prism) / exact < 0.002);
            }
        }
    }

    #[test]
    fn torus_is_closed_and_close_to_analytic() {
        for (maj, min) in [(3, 3), (16, 8), (96, 48)] {
            let (big_r, r) = (1.0, 0.25);
            let m = torus_mesh(big_r, r, maj, min);
            assert_eq!(m.vertices.len(), maj * min);
            assert_eq!(m.elements.len(), 2 * maj * min);
            assert_watertight(&m);
            assert_eq!(euler_characteristic(&m), 0);
            let v = signed_volume(&m);
            assert!(v > 0.0);
            if maj == 96 {
                let exact = 2.0 * PI * PI * big_r * r * r;
                assert!((exact - v).abs() / exact < 0.01, "{v} vs {exact}");
            }
        }
    }

    /// Cup shapes the cup tests run on: the defaults and variations of every parameter.
    fn cup_shapes() -> Vec<CupShape> {
        let d = CupShape::default();
        vec![
            d.clone(),
            CupShape {
                lip_angle_deg: 180.0,
                ..d.clone()
            },
            CupShape {
                lip_angle_deg: 60.0,
                ..d.clone()
            },
            CupShape {
                lip_angle_deg: 300.0,
                ..d.clone()
            },
            CupShape {
                lip_max_row_angle_deg: 180.0,
                ..d.clone()
            },
            CupShape {
                segments: 8,
                ..d.clone()
            },
            CupShape {
                segments: 96,
                ..d.clone()
            },
            CupShape {
                bottom_radius_m: d.rim_radius_m,
                ..d.clone()
            },
            CupShape {
                height_m: 0.05,
                rim_radius_m: 0.045,
                bottom_radius_m: 0.02,
                lip_radius_m: 0.004,
                segments: 40,
                ..d.clone()
            },
        ]
    }

    fn cup_wall_length(s: &CupShape) -> f64 {
        (s.rim_radius_m - s.bottom_radius_m).hypot(s.height_m)
    }

    /// Centre `[r, z]` of the lip's arc, from the construction: one lip radius from the rim,
    /// along the wall's outward normal.
    fn cup_lip_center(s: &CupShape) -> [f64; 2] {
        let l = cup_wall_length(s);
        [
            s.rim_radius_m + s.lip_radius_m * s.height_m / l,
            s.height_m - s.lip_radius_m * (s.rim_radius_m - s.bottom_radius_m) / l,
        ]
    }

    fn radial(p: &Vector3<f64>) -> f64 {
        p.x.hypot(p.y)
    }

    fn triangle_angles_deg(m: &Mesh<3>, t: &[usize; 3]) -> [f64; 3] {
        let p = t.map(|i| m.vertices[i]);
        [0, 1, 2].map(|k| {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            (b - a).angle(&(c - a)).to_degrees()
        })
    }

    fn edge_length_range(m: &Mesh<3>) -> (f64, f64) {
        crate::geometry::edges_from_triangles(&m.elements)
            .iter()
            .map(|e| (m.vertices[e[0]] - m.vertices[e[1]]).norm())
            .fold((f64::INFINITY, 0.0), |(lo, hi), l| (lo.min(l), hi.max(l)))
    }

    #[test]
    fn cup_lip_profile_is_the_tangent_arc() {
        for s in cup_shapes() {
            let c = cup_lip_center(&s);
            let rim = s.lip_point(0.0);
            assert!((rim[0] - s.rim_radius_m).abs() < 1e-15 && (rim[1] - s.height_m).abs() < 1e-15);
            // Tangent to the wall at the rim: the start direction is the wall's.
            let eps = 1e-7;
            let p = s.lip_point(eps);
            let l = cup_wall_length(&s);
            let wall_dir = [(s.rim_radius_m - s.bottom_radius_m) / l, s.height_m / l];
            let dir = [(p[0] - rim[0]) / eps, (p[1] - rim[1]) / eps];
            assert!((dir[0] / s.lip_radius_m - wall_dir[0]).abs() < 1e-6);
            assert!((dir[1] / s.lip_radius_m - wall_dir[1]).abs() < 1e-6);
            for k in 0..=100 {
                let q = s.lip_point(s.lip_angle_deg.to_radians() * k as f64 / 100.0);
                assert!(((q[0] - c[0]).hypot(q[1] - c[1]) - s.lip_radius_m).abs() < 1e-15);
            }
            // Curls outwards: the top of the arc is a lip radius above its centre.
            let top = c[1] + s.lip_radius_m;
            assert!(top > s.height_m);
            if s.lip_angle_deg >= 90.0 {
                assert!((s.overall_height_m() - top).abs() < 1e-15);
            }
        }
        let d = CupShape::default();
        assert!(
            (d.overall_height_m() - 0.101425).abs() < 1e-6,
            "{}",
            d.overall_height_m()
        );
        // 180° ends outside the wall pointing down (tilted inwards by the taper), 270° under the
        // curl pointing back towards the wall.
        let tau = (d.rim_radius_m - d.bottom_radius_m).atan2(d.height_m);
        let end_dir = |s: &CupShape| {
            let phi = s.lip_angle_deg.to_radians();
            let (a, b) = (s.lip_point(phi - 1e-7), s.lip_point(phi));
            (b[1] - a[1]).atan2(b[0] - a[0]).to_degrees()
        };
        assert!(
            (end_dir(&CupShape {
                lip_angle_deg: 180.0,
                ..d.clone()
            }) - (-90.0 - tau.to_degrees()))
            .abs()
                < 1e-4
        );
        assert!((end_dir(&d).abs() - (180.0 - tau.to_degrees())).abs() < 1e-4);
    }

    #[test]
    fn cup_is_one_manifold_sheet_with_one_boundary_loop_at_the_lip_end() {
        for s in cup_shapes() {
            let m = cup_mesh(&s).unwrap();
            let mut directed: HashMap<[usize; 2], usize> = HashMap::new();
            for t in &m.elements {
                assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
                for k in 0..3 {
                    *directed.entry([t[k], t[(k + 1) % 3]]).or_default() += 1;
                }
            }
            // At most 2 triangles per edge, in opposite directions (consistent orientation).
            assert!(
                directed.values().all(|&n| n == 1),
                "{s:?}: a directed edge is used twice"
            );
            let boundary: Vec<[usize; 2]> = directed
                .keys()
                .copied()
                .filter(|&[a, b]| !directed.contains_key(&[b, a]))
                .collect();
            // The boundary edges form exactly one closed loop.
            let next: HashMap<usize, usize> = boundary.iter().map(|&[a, b]| (a, b)).collect();
            assert_eq!(next.len(), boundary.len(), "a boundary vertex has two outgoing edges");
            let start = boundary[0][0];
            let (mut v, mut steps) = (start, 0);
            loop {
                v = next[&v];
                steps += 1;
                if v == start {
                    break;
                }
                assert!(steps <= boundary.len());
            }
            assert_eq!(steps, boundary.len(), "{s:?}: more than one boundary loop");
            // ... at the lip's end.
            let end = s.lip_point(s.lip_angle_deg.to_radians());
            for &[a, _] in &boundary {
                let p = m.vertices[a];
                assert!(
                    (radial(&p) - end[0]).abs() < 1e-12 && (p.z - end[1]).abs() < 1e-12,
                    "{p:?} vs {end:?}"
                );
            }
            let on_end_ring = m
                .vertices
                .iter()
                .filter(|p| (radial(p) - end[0]).abs() < 1e-12 && (p.z - end[1]).abs() < 1e-12)
                .count();
            assert_eq!(on_end_ring, boundary.len());
            // Every vertex used, no duplicates, one connected piece of disk topology.
            let mut used = vec![false; m.vertices.len()];
            m.elements.iter().flatten().for_each(|&i| used[i] = true);
            assert!(used.iter().all(|&u| u));
            let merged = crate::geometry::merge_by_distance(&m.vertices, &m.elements, 1e-9).unwrap();
            assert_eq!(merged.vertices.len(), m.vertices.len(), "duplicate vertices");
            let mut parent: Vec<usize> = (0..m.vertices.len()).collect();
            fn root(p: &mut [usize], mut i: usize) -> usize {
                while p[i] != i {
                    p[i] = p[p[i]];
                    i = p[i];
                }
                i
            }
            for t in &m.elements {
                for k in 1..3 {
                    let (a, b) = (root(&mut parent, t[0]), root(&mut parent, t[k]));
                    parent[a] = b;
                }
            }
            let r0 = root(&mut parent, 0);
            assert!(
                (0..m.vertices.len()).all(|i| root(&mut parent, i) == r0),
                "not connected"
            );
            assert_eq!(euler_characteristic(&m), 1);
        }
    }

    #[test]
    fn cup_vertices_lie_on_the_cup_and_normals_point_out_of_it() {
        for s in cup_shapes() {
            let m = cup_mesh(&s).unwrap();
            let (rb, rr, h) = (s.bottom_radius_m, s.rim_radius_m, s.height_m);
            let l = cup_wall_length(&s);
            let c = cup_lip_center(&s);
            let tol = 1e-12;
            let on_bottom = |p: &Vector3<f64>| p.z.abs() < tol && radial(p) <= rb + tol;
            let on_wall = |p: &Vector3<f64>| {
                (-tol..=h + tol).contains(&p.z) && (radial(p) - (rb + (rr - rb) * p.z / h)).abs() < tol
            };
            let on_lip = |p: &Vector3<f64>| ((radial(p) - c[0]).hypot(p.z - c[1]) - s.lip_radius_m).abs() < tol;
            assert!(m.vertices.iter().all(|p| on_bottom(p) || on_wall(p) || on_lip(p)));
            let (mut n_bottom, mut n_wall, mut n_lip) = (0, 0, 0);
            for t in &m.elements {
                let p = t.map(|i| m.vertices[i]);
                let n = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
                let mid = (p[0] + p[1] + p[2]) / 3.0;
                let e_r = Vector3::new(mid.x, mid.y, 0.0).normalize();
                if p.iter().all(on_bottom) {
                    n_bottom += 1;
                    assert!(n.z < -1.0 + 1e-9, "bottom normal {n:?}");
                } else if p.iter().all(on_wall) {
                    n_wall += 1;
                    // The cone's outward normal (h/l) e_r − ((rr − rb)/l) e_z.
                    let expected = e_r * (h / l) - Vector3::z() * ((rr - rb) / l);
                    assert!(n.dot(&expected) > 0.95, "wall normal {n:?} vs {expected:?}");
                } else {
                    n_lip += 1;
                    assert!(p.iter().all(on_lip));
                    // Towards the arc's centre circle: the wall's outer side rolled over.
                    let center = e_r * c[0] + Vector3::z() * c[1];
                    assert!(n.dot(&(center - mid).normalize()) > 0.5, "lip normal {n:?}");
                }
            }
            assert!(n_bottom > 0 && n_wall > 0 && n_lip > 0);
        }
    }

    #[test]
    fn cup_area_and_enclosed_volume_match_the_analytic_shape() {
        for s in cup_shapes() {
            let m = cup_mesh(&s).unwrap();
            let (rb, rr, h) = (s.bottom_radius_m, s.rim_radius_m, s.height_m);
            let l = cup_wall_length(&s);
            // Lip: 2π ∫ r ds and ∫ π r² dz along the arc (midpoint rule, fine enough to be exact
            // at this tolerance).
            let samples = 20_000;
            let phi_l = s.lip_angle_deg.to_radians();
            let (mut lip_area, mut lip_volume) = (0.0, 0.0);
            for k in 0..samples {
                let (a, b) = (
                    s.lip_point(phi_l * k as f64 / samples as f64),
                    s.lip_point(phi_l * (k + 1) as f64 / samples as f64),
                );
                let r_mid = 0.5 * (a[0] + b[0]);
                lip_area += 2.0 * PI * r_mid * (b[0] - a[0]).hypot(b[1] - a[1]);
                lip_volume += PI * r_mid * r_mid * (b[1] - a[1]);
            }
            let area = PI * rb * rb + PI * (rb + rr) * l + lip_area;
            // Volume closed by the plane disk through the lip's end (Green: ∮ π r² dz).
            let volume = PI * h * (rb * rb + rb * rr + rr * rr) / 3.0 + lip_volume;

            let mesh_area: f64 = m
                .elements
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.vertices[i]);
                    0.5 * (b - a).cross(&(c - a)).norm()
                })
                .sum();
            let z_end = s.lip_point(phi_l)[1];
            let o = Vector3::new(0.0, 0.0, z_end);
            let mesh_volume: f64 = m
                .elements
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.vertices[i] - o);
                    a.dot(&b.cross(&c)) / 6.0
                })
                .sum();
            let tol = if s.segments < 16 { 0.08 } else { 0.02 };
            assert!(
                (mesh_area - area).abs() < tol * area,
                "{s:?}: area {mesh_area} vs {area}"
            );
            assert!(
                (mesh_volume - volume).abs() < tol * volume,
                "{s:?}: volume {mesh_volume} vs {volume}"
            );
            if s == CupShape::default() {
                assert!((mesh_area - area).abs() < 0.005 * area, "area {mesh_area} vs {area}");
                assert!(
                    (mesh_volume - volume).abs() < 0.005 * volume,
                    "volume {mesh_volume} vs {volume}"
                );
            }
        }
    }

    #[test]
    fn cup_triangles_are_well_shaped() {
        for s in cup_shapes() {
            let m = cup_mesh(&s).unwrap();
            let min_angle = m
                .elements
                .iter()
                .flat_map(|t| triangle_angles_deg(&m, t))
                .fold(f64::INFINITY, f64::min);
            let (lo, hi) = edge_length_range(&m);
            assert!(min_angle > 25.0, "{s:?}: smallest angle {min_angle}°");
            // The lip's rings get at most 8 times the rim's density, so a very coarse wall
            // (8 segments) next to the refined lip spans more than the usual factor of ~3.
            let min_ratio = if s.segments < 16 { 0.06 } else { 0.2 };
            assert!(lo / hi > min_ratio, "{s:?}: edges from {lo} to {hi}");
        }
        let d = CupShape::default();
        let m = cup_mesh(&d).unwrap();
        let (lo, hi) = edge_length_range(&m);
        let h_rim = 2.0 * PI * d.rim_radius_m / d.segments as f64;
        assert!(
            lo > 0.3 * h_rim && hi < 1.2 * h_rim,
            "edges from {lo} to {hi}, rim spacing {h_rim}"
        );
        // Without lip refinement all edges are about the wall's spacing.
        let m = cup_mesh(&CupShape {
            lip_max_row_angle_deg: 180.0,
            ..d
        })
        .unwrap();
        let (lo, hi) = edge_length_range(&m);
        assert!(lo / hi > 0.5, "edges from {lo} to {hi}");
    }

    #[test]
    fn cup_does_not_intersect_itself() {
        for s in cup_shapes() {
            let m = cup_mesh(&s).unwrap();
            let edges = crate::geometry::edges_from_triangles(&m.elements);
            let hits = crate::geometry::intersection::find_edge_triangle_intersections(
                &m.vertices,
                &edges,
                &m.elements,
                |e, t| !m.elements[t].contains(&edges[e][0]) && !m.elements[t].contains(&edges[e][1]),
            )
            .unwrap();
            assert!(
                hits.is_empty(),
                "{s:?}: {} intersecting edge-triangle pairs",
                hits.len()
            );
        }
    }

    const CUP_DEFAULT_VERTICES: usize = 2958;
    const CUP_DEFAULT_TRIANGLES: usize = 5782;

    #[test]
    fn cup_default_counts() {
        let m = cup_mesh(&CupShape::default()).unwrap();
        assert_eq!(
            (m.vertices.len(), m.elements.len()),
            (CUP_DEFAULT_VERTICES, CUP_DEFAULT_TRIANGLES)
        );
    }

    #[test]
    fn cup_rejects_bad_parameters_naming_the_field() {
        let d = CupShape::default();
        let cases = [
            (
                CupShape {
                    height_m: 0.0,
                    ..d.clone()
                },
                "height_m",
            ),
            (
                CupShape {
                    height_m: f64::INFINITY,
                    ..d.clone()
                },
                "height_m",
            ),
            (
                CupShape {
                    rim_radius_m: -0.01,
                    ..d.clone()
                },
                "rim_radius_m",
            ),
            (
                CupShape {
                    bottom_radius_m: f64::NAN,
                    ..d.clone()
                },
                "bottom_radius_m",
            ),
            (
                CupShape {
                    bottom_radius_m: 0.03,
                    ..d.clone()
                },
                "bottom_radius_m",
            ),
            (
                CupShape {
                    lip_radius_m: 0.0,
                    ..d.clone()
                },
                "lip_radius_m",
            ),
            (
                CupShape {
                    lip_radius_m: 0.01,
                    ..d.clone()
                },
                "lip_radius_m",
            ),
            (
                CupShape {
                    lip_angle_deg: 0.0,
                    ..d.clone()
                },
                "lip_angle_deg",
            ),
            (
                CupShape {
                    lip_angle_deg: 360.0,
                    ..d.clone()
                },
                "lip_angle_deg",
            ),
            (
                CupShape {
                    lip_max_row_angle_deg: 1.0,
                    ..d.clone()
                },
                "lip_max_row_angle_deg",
            ),
            (
                CupShape {
                    segments: 7,
                    ..d.clone()
                },
                "segments",
            ),
        ];
        for (shape, field) in cases {
            let err = cup_mesh(&shape).expect_err(field).to_string();
            assert!(err.contains(&format!("`{field}`")), "{err}");
        }
    }

    #[test]
    #[should_panic(expected = "tet_grid: hexes must be positive")]
    fn tet_grid_rejects_zero_hexes() {
        let _ = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), [1, 0, 1]);
    }
}
