//! Tests of the mesh utilities: topology, measures, merging and transforms.

use super::*;
use crate::presets::meshes::{box_mesh, sphere_mesh, tet_grid, triangle_grid};
use nalgebra::Rotation3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn unit_tet() -> (Vec<Vector3<f64>>, Vec<[usize; 4]>) {
    (
        vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
        ],
        vec![[0, 1, 2, 3]],
    )
}

fn surface_volume(vertices: &[Vector3<f64>], triangles: &[[usize; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| vertices[t[0]].dot(&vertices[t[1]].cross(&vertices[t[2]])) / 6.0)
        .sum()
}

#[test]
fn surface_of_single_tet_is_outward() {
    let (v, t) = unit_tet();
    let tris = find_surface_triangles(&t).unwrap();
    assert_eq!(tris, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
    let centroid = v.iter().sum::<Vector3<f64>>() / 4.0;
    for tri in &tris {
        let [a, b, c] = tri.map(|i| v[i]);
        let n = (b - a).cross(&(c - a));
        assert!(n.dot(&((a + b + c) / 3.0 - centroid)) > 0.0);
    }
}

#[test]
fn surface_of_tet_grid_is_closed_box() {
    let size = Vector3::new(0.5, 0.4, 0.3);
    let m = tet_grid(Vector3::new(1.0, 0.0, 0.0), size, [3, 4, 5]);
    let (tris, map) = find_surface(&m.elements).unwrap();
    assert_eq!(tris.len(), 4 * (3 * 4 + 4 * 5 + 3 * 5));
    // Only corner vertices lie on the surface; centres never do.
    assert_eq!(map.len(), 4 * 5 * 6 - 2 * 3 * 4);
    let n_corners = 4 * 5 * 6;
    assert!(map.iter().all(|&i| i < n_corners));
    let surf_vertices: Vec<_> = map.iter().map(|&i| m.vertices[i]).collect();
    // Positive enclosed volume equal to the box (closed and outward).
    let vol = surface_volume(&surf_vertices, &tris);
    assert!((vol - size.x * size.y * size.z).abs() < 1e-12);
    // Original-indexing variant agrees through the map.
    let orig = find_surface_triangles(&m.elements).unwrap();
    let mapped: Vec<_> = tris.iter().map(|t| t.map(|i| map[i])).collect();
    assert_eq!(orig, mapped);
    // A closed surface: every edge is a hinge.
    assert!(perimeter_edges(&tris).is_empty());
    assert_eq!(find_hinges(&tris).unwrap().len(), 3 * tris.len() / 2);
}

#[test]
fn surface_rejects_non_manifold_and_degenerate_tets() {
    let tets = [[0, 1, 2, 3], [0, 2, 1, 4], [0, 1, 2, 5]];
    let err = find_surface(&tets).unwrap_err();
    assert_eq!(
        err,
        MeshError::NonManifoldFace {
            face: [0, 1, 2],
            count: 3
        }
    );
    assert_eq!(err.to_string(), "face (0, 1, 2) is shared by 3 tets");
    let err = find_surface(&[[0, 1, 1, 2]]).unwrap_err();
    assert_eq!(err.to_string(), "tet 0: vertex 1 appears more than once");
}

#[test]
fn reduce_connectivity_first_appearance() {
    let (tris, map) = reduce_connectivity(&[[7, 3, 9], [9, 3, 4]]);
    assert_eq!(tris, vec![[0, 1, 2], [2, 1, 3]]);
    assert_eq!(map, vec![7, 3, 9, 4]);
}

#[test]
fn edges_unique_sorted() {
    assert_eq!(
        edges_from_triangles(&[[2, 1, 0], [0, 2, 3]]),
        vec![[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]]
    );
    let (_, t) = unit_tet();
    assert_eq!(edges_from_tets(&t).len(), 6);
    let m = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), [2, 2, 2]);
    let e = edges_from_tets(&m.elements);
    assert!(e.windows(2).all(|w| w[0] < w[1]));
    assert!(e.iter().all(|e| e[0] < e[1]));
    // Euler for a tetrahedralised ball: V - E + F - T = 1.
    let faces = {
        let mut f: Vec<[usize; 3]> = m
            .elements
            .iter()
            .flat_map(|t| {
                let mut fs = outward_tet_faces(t);
                fs.iter_mut().for_each(|f| f.sort_unstable());
                fs
            })
            .collect();
        f.sort_unstable();
        f.dedup();
        f.len()
    };
    let chi = m.vertices.len() as i64 - e.len() as i64 + faces as i64 - m.elements.len() as i64;
    assert_eq!(chi, 1);
}

#[test]
fn hinges_flat_grid_have_zero_dihedral_angle() {
    let m = triangle_grid([0.0, 0.0], [1.0, 1.0], [4, 3], 0.0);
    let hinges = find_hinges(&m.elements).unwrap();
    let n_edges = edges_from_triangles(&m.elements).len();
    let n_boundary = perimeter_edges(&m.elements).len();
    assert_eq!(n_boundary, 2 * (4 + 3));
    assert_eq!(hinges.len(), n_edges - n_boundary);
    for h in &hinges {
        assert!(h[0] < h[1]);
        let [x0, x1, x2, x3] = h.map(|i| m.vertices[i]);
        let n_a = (x1 - x0).cross(&(x2 - x0));
        let n_b = -(x1 - x0).cross(&(x3 - x0));
        assert!(n_a.z > 0.0 && n_b.z > 0.0, "hinge {h:?}");
        // Stark's acos formula gives (almost) zero.
        let angle = ((1.0 - 1e-12) * n_a.normalize().dot(&n_b.normalize())).acos();
        assert!(angle < 1e-5);
    }
    // First hinges of the 4x3 grid (vertex (i, j) = 4 i + j). Edge [0, 5], the first
    // quad's diagonal: triangles [0, 4, 5] (traverses 5 -> 0) and [0, 5, 1] (0 -> 5).
    // Edge [1, 5]: [0, 5, 1] (5 -> 1) and [1, 5, 2] (1 -> 5). Edge [2, 5]: [1, 5, 2]
    // (5 -> 2) and [5, 6, 2] (2 -> 5).
    assert_eq!(&hinges[..3], &[[0, 5, 1, 4], [1, 5, 2, 0], [2, 5, 6, 1]]);
}

#[test]
fn hinge_sign_tells_folds_apart() {
    // Two triangles folded up along the x axis: a valley seen from +z.
    let v: Vec<Vector3<f64>> = vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.5, 1.0, 1.0),
        Vector3::new(0.5, -1.0, 1.0),
    ];
    let tris = [[0, 1, 2], [1, 0, 3]];
    let h = find_hinges(&tris).unwrap();
    assert_eq!(h, vec![[0, 1, 2, 3]]);
    let [x0, x1, x2, x3] = h[0].map(|i| v[i]);
    let n_a = (x1 - x0).cross(&(x2 - x0));
    let n_b = -(x1 - x0).cross(&(x3 - x0));
    let angle = n_a.normalize().dot(&n_b.normalize()).acos();
    assert!((angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert_eq!(sharp_edges(&v, &tris, 80.0).unwrap(), vec![[0, 1]]);
    assert!(sharp_edges(&v, &tris, 100.0).unwrap().is_empty());
}

#[test]
fn hinges_reject_non_manifold_edge() {
    let tris = [[3, 7, 0], [7, 3, 1], [3, 7, 2]];
    let err = find_hinges(&tris).unwrap_err();
    assert_eq!(err.to_string(), "edge (3, 7) is shared by 3 triangles");
}

#[test]
fn perimeter_keeps_triangle_direction() {
    let m = triangle_grid([0.0, 0.0], [1.0, 1.0], [1, 1], 0.0);
    // Quad [0,2,3],[0,3,1] (counter-clockwise about +z): boundary 0->2->3->1->0.
    let p = perimeter_edges(&m.elements);
    assert_eq!(p, vec![[1, 0], [0, 2], [3, 1], [2, 3]]);
}

#[test]
fn sharp_edges_of_box_are_its_12_edges() {
    let b = box_mesh(Vector3::repeat(1.0));
    let sharp = sharp_edges(&b.vertices, &b.elements, 30.0).unwrap();
    assert_eq!(sharp.len(), 12);
    for [a, c] in sharp {
        let d = b.vertices[a] - b.vertices[c];
        assert!((d.norm() - 1.0).abs() < 1e-12, "diagonal reported as sharp");
    }
    let s = sphere_mesh(1.0, 3);
    assert!(sharp_edges(&s.vertices, &s.elements, 30.0).unwrap().is_empty());
}

#[test]
fn measures_and_volume_check() {
    let (v, mut t) = unit_tet();
    assert!((tet_signed_volumes(&v, &t)[0] - 1.0 / 6.0).abs() < 1e-15);
    assert!(check_tet_volumes(&v, &t).is_ok());
    t[0].swap(0, 1);
    let err = check_tet_volumes(&v, &t).unwrap_err();
    assert!(matches!(err, MeshError::NonPositiveVolume { tet: 0, volume } if volume < 0.0));
    assert_eq!(
        err.to_string(),
        "tet 0: rest volume -1.6666666666666666e-1 m³ is not positive"
    );
    assert_eq!(fix_tet_orientation(&v, &mut t), 1);
    assert!(check_tet_volumes(&v, &t).is_ok());
    let tiny = vec![v[0], v[1], v[2], Vector3::new(0.0, 0.0, -7.2e-9)];
    let err = check_tet_volumes(&tiny, &[[0, 1, 2, 3]]).unwrap_err();
    assert_eq!(err.to_string(), "tet 0: rest volume -1.2e-9 m³ is not positive");
    let err = check_tet_volumes(&v, &[[0, 1, 2, 9]]).unwrap_err();
    assert_eq!(
        err.to_string(),
        "tet 0: vertex index 9 is out of range (the mesh has 4 vertices)"
    );
    assert_eq!(triangle_areas(&v, &[[0, 1, 2]]), vec![0.5]);
    assert_eq!(segment_lengths(&v, &[[1, 2]]), vec![2f64.sqrt()]);
    let n = triangle_normal(&v[0], &v[1], &v[2]);
    assert_eq!(n, Vector3::new(0.0, 0.0, 1.0));
}

#[test]
fn lumped_masses_sum_to_total() {
    let m = tet_grid(Vector3::zeros(), Vector3::new(0.5, 0.5, 0.5), [3, 3, 3]);
    let masses = lumped_masses_from_tets(&m.vertices, &m.elements, 1000.0);
    let total: f64 = masses.iter().sum();
    assert!((total - 125.0).abs() < 1e-9);
    assert!(masses.iter().all(|&x| x > 0.0));
    assert!((total_tet_volume(&m.vertices, &m.elements) - 0.125).abs() < 1e-14);

    let g = triangle_grid([0.0, 0.0], [2.0, 1.0], [4, 2], 0.0);
    let masses = lumped_masses_from_triangles(&g.vertices, &g.elements, 0.2);
    assert!((masses.iter().sum::<f64>() - 0.4).abs() < 1e-14);
    // Corner vertex 0 touches two triangles of area 0.125 each (quad (0,0) is "even").
    assert!((masses[0] - 0.2 * 2.0 * 0.125 / 3.0).abs() < 1e-15);

    let v = vec![
        Vector3::zeros(),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(1.0, 2.0, 0.0),
    ];
    let masses = lumped_masses_from_segments(&v, &[[0, 1], [1, 2]], 0.05);
    for (m, expected) in masses.iter().zip([0.025, 0.075, 0.05]) {
        assert!((m - expected).abs() < 1e-15);
    }
}

#[test]
fn merge_welds_duplicates_and_drops_degenerates() {
    // Two triangles of a quad stored with duplicated seam vertices (plus jitter).
    let v = vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(1.0, 1.0, 0.0),
        Vector3::new(0.0, 0.0, 1e-9),
        Vector3::new(1.0 - 1e-9, 1.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
    ];
    let tris = [[0, 1, 2], [3, 4, 5], [0, 1, 2], [0, 3, 5]];
    let merged = merge_by_distance(&v, &tris, 1e-6).unwrap();
    assert_eq!(merged.vertices.len(), 4);
    assert_eq!(merged.old_to_new, vec![0, 1, 2, 0, 2, 3]);
    assert_eq!(merged.elements, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(merged.kept_elements, vec![0, 1]);
    // Exact mode keeps the jittered copies apart.
    let exact = merge_by_distance(&v, &tris, 0.0).unwrap();
    assert_eq!(exact.vertices.len(), 6);
    assert_eq!(exact.elements.len(), 3);
    assert!(matches!(
        merge_by_distance(&v, &tris, -1.0),
        Err(MeshError::InvalidTolerance { .. })
    ));
    assert!(matches!(
        merge_by_distance(&v, &[[0, 1, 99]], 0.1),
        Err(MeshError::IndexOutOfRange { vertex: 99, .. })
    ));
}

#[test]
fn merge_matches_brute_force_on_random_points() {
    let mut rng = StdRng::seed_from_u64(0);
    let tol = 0.05;
    let v: Vec<Vector3<f64>> = (0..400)
        .map(|_| Vector3::new(rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>()) * 0.6)
        .collect();
    let merged = merge_by_distance::<1>(&v, &[], tol).unwrap();
    // Reference: greedy in order, earliest kept representative within tolerance.
    let mut kept: Vec<Vector3<f64>> = Vec::new();
    let mut map = Vec::new();
    for p in &v {
        match kept.iter().position(|k| (k - p).norm_squared() <= tol * tol) {
            Some(i) => map.push(i),
            None => {
                kept.push(*p);
                map.push(kept.len() - 1);
            }
        }
    }
    assert_eq!(merged.old_to_new, map);
    assert_eq!(merged.vertices, kept);
}

#[test]
fn transforms() {
    let mut p = vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(3.0, 2.0, 0.0)];
    translate(&mut p, &Vector3::new(0.0, 0.0, 1.0));
    assert_eq!(p[0], Vector3::new(1.0, 0.0, 1.0));
    let c = center(&mut p);
    assert_eq!(c, Vector3::new(2.0, 1.0, 1.0));
    assert_eq!(p[0], Vector3::new(-1.0, -1.0, 0.0));
    rotate_deg(&mut p, 90.0, &Vector3::z());
    assert!((p[0] - Vector3::new(1.0, -1.0, 0.0)).norm() < 1e-15);
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), -std::f64::consts::FRAC_PI_2);
    rotate(&mut p, &r);
    assert!((p[0] - Vector3::new(-1.0, -1.0, 0.0)).norm() < 1e-15);
    let q = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    rotate_about(&mut p, &q, &Vector3::new(0.0, 1.0, 0.0));
    assert!((p[0] - Vector3::new(-1.0, 3.0, 0.0)).norm() < 1e-14);
    scale(&mut p, 2.0);
    scale_xyz(&mut p, &Vector3::new(1.0, 0.5, 1.0));
    assert!((p[0] - Vector3::new(-2.0, 3.0, 0.0)).norm() < 1e-14);
    mirror(&mut p, 0, 1.0);
    assert!((p[0] - Vector3::new(4.0, 3.0, 0.0)).norm() < 1e-14);
    let (lo, hi) = bounding_box(&p).unwrap();
    assert!(lo <= hi);
    assert!(bounding_box(&[]).is_none());
}

#[test]
fn vertex_normals_of_sphere_point_outward() {
    let s = sphere_mesh(2.0, 2);
    let n = vertex_normals(&s.vertices, &s.elements);
    for (v, n) in s.vertices.iter().zip(&n) {
        assert!((n.norm() - 1.0).abs() < 1e-12);
        assert!(n.dot(&v.normalize()) > 0.99);
    }
}
