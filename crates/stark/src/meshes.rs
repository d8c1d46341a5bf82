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
//!
//! The grids and the [`Mesh`] types are here, the closed meshes in `meshes/closed.rs`, the cup in
//! `meshes/cup.rs`.

mod closed;
mod cup;

use std::f64::consts::PI;

use nalgebra::Vector3;

pub use closed::{box_mesh, capsule_mesh, cylinder_mesh, sphere_mesh, torus_mesh};
pub use cup::{cup_mesh, CupShape};

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

#[cfg(test)]
mod tests;
