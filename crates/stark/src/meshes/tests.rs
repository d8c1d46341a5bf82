//! Tests of the mesh generators: Stark's grid orderings, closed meshes' volumes and the cup's shape.

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
        let on_wall =
            |p: &Vector3<f64>| (-tol..=h + tol).contains(&p.z) && (radial(p) - (rb + (rr - rb) * p.z / h)).abs() < tol;
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
