//! Tests of the mesh file readers and writers.
use super::*;
use crate::geometry::mesh::{check_tet_volumes, find_surface};
use crate::io::vtk::{VtkCells, VtkEncoding, VtkWriter};
use crate::presets::meshes::{box_mesh, tet_grid};

const CUBE_OBJ: &str = "# cube as two shapes sharing vertices\n\
    v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
    o bottom_and_top\nf 1 4 3 2\nf 5 6 7 8\n\
    o sides\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

const TET_MSH: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n\
    $PhysicalNames\n1\n3 1 \"solid\"\n$EndPhysicalNames\n\
    $Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n\
    $Nodes\n2 5 1 5\n\
    0 1 0 1\n1\n0 0 0\n\
    3 1 0 4\n2\n3\n4\n5\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n\
    $EndNodes\n\
    $Elements\n3 4 1 4\n\
    0 1 15 1\n1 1\n\
    2 1 2 1\n2 1 2 3\n\
    3 1 4 2\n3 1 2 3 4\n4 2 3 4 5\n\
    $EndElements\n";

fn write(dir: &Path, name: &str, contents: &[u8]) -> PathBuf {
    let p = dir.join(name);
    fs::write(&p, contents).unwrap();
    p
}

#[test]
fn obj_shapes_and_merged() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "cube.obj", CUBE_OBJ.as_bytes());
    let shapes = load_obj_shapes(&p).unwrap();
    assert_eq!(shapes.len(), 2);
    assert_eq!(shapes[0].0, "bottom_and_top");
    assert_eq!((shapes[0].1.vertices.len(), shapes[0].1.elements.len()), (8, 4));
    assert_eq!((shapes[1].1.vertices.len(), shapes[1].1.elements.len()), (8, 8));
    let merged = load_obj(&p).unwrap();
    assert_eq!(merged.vertices.len(), 8);
    assert_eq!(merged.elements.len(), 12);
    // Closed and outward: the (unit) cube's signed volume is 1.
    let vol: f64 = merged
        .elements
        .iter()
        .map(|t| merged.vertices[t[0]].dot(&merged.vertices[t[1]].cross(&merged.vertices[t[2]])) / 6.0)
        .sum();
    assert!((vol - 1.0).abs() < 1e-12);
    let via_dispatch = load_mesh(dir.path().join("cube.obj")).unwrap();
    assert_eq!(via_dispatch.triangles.len(), 12);
    assert!(via_dispatch.tets.is_empty());
}

#[test]
fn obj_text_parses_in_file_order_and_names_itself_in_errors() {
    let m = parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2/5 3 4\n", "quad.obj").unwrap();
    assert_eq!(m.vertices.len(), 4);
    assert_eq!(m.elements.len(), 2, "the quad is triangulated");
    let e = parse_obj("v 0 0 x\nf 1 1 1\n", "bad.obj").unwrap_err().to_string();
    assert!(e.contains("bad.obj"), "{e}");
}

#[test]
fn obj_errors() {
    let dir = tempfile::tempdir().unwrap();
    let err = load_obj(dir.path().join("cup.obj")).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!("file '{}' not found", dir.path().join("cup.obj").display())
    );
    let p = write(dir.path(), "bad.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    let err = load_obj(&p).unwrap_err();
    assert!(matches!(err, MeshFileError::Obj { .. }), "{err}");
    assert!(err.to_string().contains("cannot parse OBJ"), "{err}");
    let p = write(dir.path(), "lines.obj", b"v 0 0 0\nv 1 0 0\nl 1 2\n");
    let err = load_triangle_mesh(&p).unwrap_err();
    assert_eq!(err.to_string(), format!("'{}' contains no triangles", p.display()));
}

#[test]
fn stl_binary_and_ascii_are_welded() {
    let dir = tempfile::tempdir().unwrap();
    let b = box_mesh(Vector3::new(1.0, 2.0, 0.5));
    let triangles: Vec<stl_io::Triangle> = b
        .elements
        .iter()
        .map(|t| {
            let v = t.map(|i| {
                let p = b.vertices[i];
                stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32])
            });
            stl_io::Triangle {
                normal: stl_io::Normal::new([0.0, 0.0, 0.0]),
                vertices: v,
            }
        })
        .collect();
    let mut bytes = Vec::new();
    stl_io::write_stl(&mut bytes, triangles.iter()).unwrap();
    let p = write(dir.path(), "box.STL", &bytes);
    let m = load_stl(&p).unwrap();
    assert_eq!((m.vertices.len(), m.elements.len()), (8, 12));
    let via_dispatch = load_triangle_mesh(&p).unwrap();
    assert_eq!(via_dispatch, m);

    let ascii =
        "solid tri\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n\
        facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid tri\n";
    let p = write(dir.path(), "quad.stl", ascii.as_bytes());
    let m = load_stl(&p).unwrap();
    assert_eq!((m.vertices.len(), m.elements.len()), (4, 2));

    // Truncated binary: header says 12 triangles, data stops early.
    let p = write(dir.path(), "cut.stl", &bytes[..bytes.len() - 30]);
    let err = load_stl(&p).unwrap_err();
    assert!(matches!(err, MeshFileError::Stl { .. }), "{err}");
}

#[test]
fn vtk_tet_mesh_roundtrip() {
    let dir = tempfile::tempdir().unwrap();
    let m = tet_grid(Vector3::zeros(), Vector3::repeat(0.1), [2, 2, 2]);
    for (name, encoding) in [("a.vtk", VtkEncoding::Ascii), ("b.VTK", VtkEncoding::Binary)] {
        let p = dir.path().join(name);
        VtkWriter::new(&m.vertices, VtkCells::Tets(&m.elements))
            .encoding(encoding)
            .write(&p)
            .unwrap();
        let loaded = load_tet_mesh(&p).unwrap();
        assert_eq!(loaded, m);
        assert!(matches!(
            load_triangle_mesh(&p),
            Err(MeshFileError::NoElements { what: "triangles", .. })
        ));
    }
}

#[test]
fn msh_tets_and_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "two_tets.msh", TET_MSH.as_bytes());
    let m = load_mesh(&p).unwrap();
    assert_eq!(m.vertices.len(), 5);
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    assert_eq!(m.tets, vec![[0, 1, 2, 3], [1, 2, 3, 4]]);
    let tets = load_tet_mesh(&p).unwrap();
    check_tet_volumes(&tets.vertices, &tets.elements).unwrap();
    let (surface, _) = find_surface(&tets.elements).unwrap();
    assert_eq!(surface.len(), 6);
}

#[test]
fn msh_errors_name_the_line() {
    let path = Path::new("mesh.msh");
    let err = |text: &str| parse_msh(text, path).unwrap_err().to_string();
    assert_eq!(
        err(&TET_MSH.replace("4.1 0 8", "2.2 0 8")),
        "'mesh.msh' line 2: Gmsh format version 2.2 is not supported (expected 4.1; re-export with `gmsh -format msh41`)"
    );
    assert_eq!(
        err(&TET_MSH.replace("4.1 0 8", "4.1 1 8")),
        "'mesh.msh' line 2: binary .msh files are not supported (expected ASCII, file type 0)"
    );
    assert_eq!(
        err(&TET_MSH.replace("3 1 4 2\n", "3 1 5 2\n")),
        "'mesh.msh' line 33: Gmsh element type 5 (8-node hexahedron) is not supported (expected 2: triangle, 4: tetrahedron; 1 and 15 are skipped)"
    );
    assert_eq!(
        err(&TET_MSH.replace("4 2 3 4 5\n", "4 2 3 4 9\n")),
        "'mesh.msh' line 35: element references node 9, which $Nodes does not define"
    );
    assert_eq!(
        err(&TET_MSH.replace("0 1 0\n0 0 1", "0 one 0\n0 0 1")),
        "'mesh.msh' line 23: expected a node y coordinate, found 'one'"
    );
    let cut = &TET_MSH[..TET_MSH.find("4 2 3 4 5").unwrap()];
    assert_eq!(
        err(cut),
        "'mesh.msh' line 34: unexpected end of file, expected an element tag"
    );
    assert!(err("hello").contains("expected a section such as $MeshFormat, found 'hello'"));
}

#[test]
fn dispatch_errors() {
    let dir = tempfile::tempdir().unwrap();
    let err = load_mesh("foo.xyz").unwrap_err();
    assert_eq!(
        err.to_string(),
        "unknown mesh file extension `.xyz` in 'foo.xyz' (expected .obj, .stl, .dae, .vtk, .msh)"
    );
    let err = load_mesh("foo").unwrap_err();
    assert!(matches!(err, MeshFileError::UnknownExtension { ref extension, .. } if extension.is_empty()));
    for name in ["missing.stl", "missing.vtk", "missing.msh", "missing.obj"] {
        let err = load_mesh(dir.path().join(name)).unwrap_err();
        assert!(err.to_string().starts_with("file '"), "{name}: {err}");
        assert!(err.to_string().ends_with("not found"), "{name}: {err}");
    }
    // A VTK file with the wrong cell type for a tet loader.
    let p = dir.path().join("tri.vtk");
    let b = box_mesh(Vector3::repeat(1.0));
    VtkWriter::new(&b.vertices, VtkCells::Triangles(&b.elements))
        .write(&p)
        .unwrap();
    let err = load_tet_mesh(&p).unwrap_err();
    assert_eq!(err.to_string(), format!("'{}' contains no tetrahedra", p.display()));
    let p = write(
        dir.path(),
        "hex.vtk",
        b"# vtk DataFile Version 4.2\nh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 8 double\n\
        0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1\nCELLS 1 9\n8 0 1 2 3 4 5 6 7\nCELL_TYPES 1\n12\n",
    );
    let err = load_mesh(&p).unwrap_err();
    assert!(
        err.to_string()
            .contains("line 9: cell 0 has VTK cell type 12 (hexahedron)"),
        "{err}"
    );
}
