//! Mesh generators.
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
//! Counts of zero (no quads, no segments, fewer than three slices, ...) are programmer errors
//! and panic with a message naming the argument.

use std::collections::HashMap;
use std::f64::consts::PI;

use nalgebra::Vector3;

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

    #[test]
    #[should_panic(expected = "tet_grid: hexes must be positive")]
    fn tet_grid_rejects_zero_hexes() {
        let _ = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), [1, 0, 1]);
    }
}
