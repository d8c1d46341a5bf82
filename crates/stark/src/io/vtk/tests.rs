//! Tests of the legacy VTK writer and reader: round trips, layouts, attributes and errors.

use super::*;
use crate::presets::meshes::{segment_line, tet_grid, triangle_grid};
use nalgebra::Vector3;

fn roundtrip(writer: &VtkWriter<'_>) -> VtkMesh {
    let bytes = writer.to_bytes().unwrap();
    parse_vtk(&bytes, "test.vtk").unwrap()
}

#[test]
fn tets_roundtrip_binary_and_ascii_with_data() {
    let m = tet_grid(Vector3::zeros(), Vector3::new(0.3, 0.2, 0.1), [2, 2, 3]);
    let velocity: Vec<_> = m.vertices.iter().map(|p| p * 2.0 + Vector3::x()).collect();
    let temperature: Vec<f64> = (0..m.vertices.len()).map(|i| i as f64 * 0.1).collect();
    let tet_ids: Vec<f64> = (0..m.elements.len()).map(|i| i as f64).collect();
    for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
        let writer = VtkWriter::new(&m.vertices, VtkCells::Tets(&m.elements))
            .encoding(encoding)
            .title("tet grid")
            .point_vectors("velocity", &velocity)
            .point_scalars("temperature", &temperature)
            .cell_scalars("id", &tet_ids);
        let r = roundtrip(&writer);
        assert_eq!(r.title, "tet grid");
        assert_eq!(r.points, m.vertices, "{encoding:?}: positions not bit-exact");
        assert_eq!(r.tets, m.elements);
        assert!(r.triangles.is_empty() && r.segments.is_empty() && r.vertices.is_empty());
        assert_eq!(r.point_attribute("velocity").unwrap().as_vectors().unwrap(), velocity);
        assert_eq!(
            r.point_attribute("temperature").unwrap().as_scalars().unwrap(),
            &temperature[..]
        );
        assert_eq!(r.cell_attribute("id").unwrap().as_scalars().unwrap(), &tet_ids[..]);
    }
}

#[test]
fn all_cell_kinds_roundtrip() {
    let g = triangle_grid([0.0, 0.0], [1.0, 1.0], [3, 2], 0.25);
    let l = segment_line(Vector3::zeros(), Vector3::new(1.0, 1.0, 1.0), 5);
    for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
        let r = roundtrip(&VtkWriter::new(&g.vertices, VtkCells::Triangles(&g.elements)).encoding(encoding));
        assert_eq!(
            (r.points.clone(), r.triangles.clone()),
            (g.vertices.clone(), g.elements.clone())
        );
        assert!(r.cell_types.iter().all(|&t| t == VtkCellType::Triangle));
        let r = roundtrip(&VtkWriter::new(&l.vertices, VtkCells::Segments(&l.elements)).encoding(encoding));
        assert_eq!(r.segments, l.elements);
        assert_eq!(r.points, l.vertices);
        let r = roundtrip(&VtkWriter::new(&l.vertices, VtkCells::Points).encoding(encoding));
        assert_eq!(r.vertices, (0..6).collect::<Vec<_>>());
        assert_eq!(r.cell_types, vec![VtkCellType::Vertex; 6]);
    }
}

#[test]
fn float32_and_awkward_values() {
    let points = vec![
        Vector3::new(1e-300, -2.5e20, 0.1),
        Vector3::new(-0.0, 123456.789, 1e-7),
        Vector3::new(f64::MAX, f64::MIN_POSITIVE, -1.0 / 3.0),
    ];
    let s = [f64::NAN, f64::INFINITY, -5e-324];
    for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
        let r = roundtrip(
            &VtkWriter::new(&points, VtkCells::Points)
                .encoding(encoding)
                .point_scalars("s", &s),
        );
        assert_eq!(r.points, points);
        let back = r.point_attribute("s").unwrap().as_scalars().unwrap().to_vec();
        assert!(back[0].is_nan() && back[1] == f64::INFINITY && back[2] == -5e-324);
        let small = [Vector3::new(0.1, 0.2, 0.3)];
        let r = roundtrip(
            &VtkWriter::new(&small, VtkCells::Points)
                .encoding(encoding)
                .precision(VtkPrecision::Float32),
        );
        assert_eq!(r.points[0].map(|c| c as f32), small[0].map(|c| c as f32));
    }
    let text = VtkWriter::new(&points[..1], VtkCells::Points)
        .encoding(VtkEncoding::Ascii)
        .precision(VtkPrecision::Float32)
        .to_bytes()
        .unwrap();
    assert!(String::from_utf8(text).unwrap().contains("POINTS 1 float\n"));
}

#[test]
fn ascii_layout_is_classic_legacy() {
    let points = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
    ];
    let text = VtkWriter::new(&points, VtkCells::Triangles(&[[0, 1, 2]]))
        .encoding(VtkEncoding::Ascii)
        .title("t")
        .cell_scalars("a", &[0.5])
        .to_bytes()
        .unwrap();
    let expected = "# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n\
        POINTS 3 double\n0 0 0\n1 0 0\n0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n\
        CELL_DATA 1\nSCALARS a double 1\nLOOKUP_TABLE default\n0.5\n";
    assert_eq!(String::from_utf8(text).unwrap(), expected);
}

#[test]
fn empty_mesh_roundtrips() {
    for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
        let r = roundtrip(&VtkWriter::new(&[], VtkCells::Triangles(&[])).encoding(encoding));
        assert!(r.points.is_empty() && r.triangles.is_empty());
    }
}

#[test]
fn writer_rejects_bad_input() {
    let p = [Vector3::zeros(), Vector3::x()];
    let err = VtkWriter::new(&p, VtkCells::Segments(&[[0, 1], [1, 2]]))
        .to_bytes()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "cannot write VTK: cell 1 references point 2 but there are only 2 points"
    );
    let err = VtkWriter::new(&p, VtkCells::Points)
        .point_scalars("s", &[1.0])
        .to_bytes()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "cannot write VTK: point data 's' has 1 values for 2 points"
    );
    let err = VtkWriter::new(&p, VtkCells::Points)
        .point_scalars("my field", &[1.0, 2.0])
        .to_bytes()
        .unwrap_err();
    assert!(err.to_string().contains("no whitespace"));
    let err = VtkWriter::new(&p, VtkCells::Points)
        .point_scalars("a", &[1.0, 2.0])
        .point_vectors("a", &p)
        .to_bytes()
        .unwrap_err();
    assert!(err.to_string().contains("used twice"));
    let err = VtkWriter::new(&p, VtkCells::Points)
        .cell_scalars("c", &[1.0])
        .to_bytes()
        .unwrap_err();
    assert!(err.to_string().contains("1 values for 2 cells"));
}

#[test]
fn write_and_read_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frame_0.vtk");
    let m = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), [1, 1, 1]);
    VtkWriter::new(&m.vertices, VtkCells::Tets(&m.elements))
        .write(&path)
        .unwrap();
    assert!(!dir.path().join("frame_0.vtk.tmp").exists());
    let r = read_vtk(&path).unwrap();
    assert_eq!(r.tets, m.elements);
    let missing = dir.path().join("nope.vtk");
    let err = read_vtk(&missing).unwrap_err();
    assert!(matches!(err, VtkError::NotFound { .. }));
    assert_eq!(err.to_string(), format!("file '{}' not found", missing.display()));
    let err = VtkWriter::new(&m.vertices, VtkCells::Points)
        .write(dir.path().join("no_dir/x.vtk"))
        .unwrap_err();
    assert!(matches!(err, VtkError::Write { .. }));
}

#[test]
fn reads_tolerant_ascii_with_comments_and_mixed_cells() {
    let text = "# vtk DataFile Version 3.0\nhand written\n\nascii\n  DATASET UNSTRUCTURED_GRID\n\
        # a comment line\n\
        POINTS 5 float\n0 0 0  1 0 0\n0 1 0\n0 0 1   1 1 1\n\n\
        CELLS 3 12\n4 0 1 2 3\n3 1 2 4\n2 0 4\n\
        CELL_TYPES 3\n10\n5\n3\n\
        CELL_DATA 3\nSCALARS mat int\n1 2 3\n\
        POINT_DATA 5\nNORMALS n float\n0 0 1 0 0 1 0 0 1 0 0 1 0 0 1\n";
    let r = parse_vtk(text.as_bytes(), "hand.vtk").unwrap();
    assert_eq!(r.points.len(), 5);
    assert_eq!(r.tets, vec![[0, 1, 2, 3]]);
    assert_eq!(r.triangles, vec![[1, 2, 4]]);
    assert_eq!(r.segments, vec![[0, 4]]);
    assert_eq!(
        r.cell_types,
        vec![VtkCellType::Tetra, VtkCellType::Triangle, VtkCellType::Line]
    );
    assert_eq!(r.cell_attribute("mat").unwrap().values, vec![1.0, 2.0, 3.0]);
    assert_eq!(r.point_attribute("n").unwrap().n_components, 3);
}

#[test]
fn reads_version_5_layout_like_meshio() {
    // As written by meshio 5.3.5 (`meshio.write(..., binary=False)`).
    let text = "# vtk DataFile Version 5.1\nwritten by meshio v5.3.5\nASCII\nDATASET UNSTRUCTURED_GRID\n\
        POINTS 4 double\n0.0 0.0 0.0 1.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 1.0\n\
        CELLS 3 7\nOFFSETS vtktypeint64\n0\n4\n7\nCONNECTIVITY vtktypeint64\n0\n1\n2\n3\n0\n1\n2\n\
        CELL_TYPES 2\n10\n5\n\
        POINT_DATA 4\nFIELD FieldData 2\nv 3 4 double\n0.0 0.0 0.0 2.0 0.0 0.0 0.0 2.0 0.0 0.0 0.0 2.0\n\
        s 1 4 double\n0.0 1.0 2.0 3.0\n\
        CELL_DATA 2\nFIELD FieldData 1\nc 1 2 double\n1.5 2.5\n";
    let r = parse_vtk(text.as_bytes(), "meshio.vtk").unwrap();
    assert_eq!(r.tets, vec![[0, 1, 2, 3]]);
    assert_eq!(r.triangles, vec![[0, 1, 2]]);
    assert_eq!(
        r.point_attribute("v").unwrap().as_vectors().unwrap()[1],
        Vector3::new(2.0, 0.0, 0.0)
    );
    assert_eq!(r.point_attribute("s").unwrap().values, vec![0.0, 1.0, 2.0, 3.0]);
    assert_eq!(r.cell_attribute("c").unwrap().values, vec![1.5, 2.5]);
}

#[test]
fn reads_version_5_binary() {
    let mut b: Vec<u8> =
        b"# vtk DataFile Version 5.1\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n".to_vec();
    for v in [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0f64] {
        b.extend_from_slice(&v.to_be_bytes());
    }
    b.extend_from_slice(b"\nCELLS 2 4\nOFFSETS vtktypeint64\n");
    for v in [0i64, 4] {
        b.extend_from_slice(&v.to_be_bytes());
    }
    b.extend_from_slice(b"\nCONNECTIVITY vtktypeint64\n");
    for v in [0i64, 1, 2, 3] {
        b.extend_from_slice(&v.to_be_bytes());
    }
    b.extend_from_slice(b"\nCELL_TYPES 1\n");
    b.extend_from_slice(&10i32.to_be_bytes());
    b.extend_from_slice(b"\n");
    let r = parse_vtk(&b, "bin5.vtk").unwrap();
    assert_eq!(r.tets, vec![[0, 1, 2, 3]]);
    assert_eq!(r.points[3], Vector3::new(0.0, 0.0, 1.0));
}

#[test]
fn parse_errors_name_file_and_line() {
    let good = "# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n\
        0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n";
    assert!(parse_vtk(good.as_bytes(), "box.vtk").is_ok());

    let err = |text: &str| parse_vtk(text.as_bytes(), "box.vtk").unwrap_err().to_string();

    assert_eq!(
        err(&good.replace("CELL_TYPES 1\n10\n", "POINT_DATA 4\n")),
        "'box.vtk' line 12: expected CELL_TYPES (CELLS given at line 10), found end of file"
    );
    assert_eq!(
        err(&good.replace("CELL_TYPES", "CELL_TYPO")),
        "'box.vtk' line 12: expected a section keyword (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, SCALARS, VECTORS, FIELD, ...), found 'CELL_TYPO 1'"
    );
    assert_eq!(
        err(&good.replace("\n10\n", "\n12\n")),
        "'box.vtk' line 12: cell 0 has VTK cell type 12 (hexahedron); only vertex (1), line (3), triangle (5) and tetra (10) are supported"
    );
    assert_eq!(
        err(&good.replace("\n10\n", "\n5\n")),
        "'box.vtk' line 10: cell 0 of type triangle has 4 vertices, expected 3"
    );
    assert_eq!(
        err(&good.replace("4 0 1 2 3", "4 0 1 2 7")),
        "'box.vtk' line 10: cell 0 references point 7 but there are only 4 points"
    );
    assert_eq!(
        err(&good.replace("0 0 1\nCELLS", "0 zero 1\nCELLS")),
        "'box.vtk' line 9: expected a number as value 11 of POINTS, found 'zero'"
    );
    let cut = &good[..good.find("0 1 0\n").unwrap()];
    assert_eq!(
        err(cut),
        "'box.vtk' line 7: unexpected end of file while reading POINTS (expected 12 values, found 6)"
    );
    assert_eq!(
        err("hello\n"),
        "'box.vtk' line 1: expected '# vtk DataFile Version x.x', found 'hello'"
    );
    assert_eq!(
        err(&good.replace("UNSTRUCTURED_GRID", "POLYDATA")),
        "'box.vtk' line 4: unsupported dataset type POLYDATA (only UNSTRUCTURED_GRID is supported)"
    );
    assert_eq!(
        err(&good.replace("ASCII", "TEXT")),
        "'box.vtk' line 3: expected ASCII or BINARY, found 'TEXT'"
    );
    assert_eq!(
        err(&good.replace("POINTS 4 double", "POINTS 4 quad")),
        "'box.vtk' line 5: unsupported data type 'quad' (expected float, double, int, ...)"
    );
    assert!(err("").contains("unexpected end of file while reading the header"));
    assert_eq!(
        err(&format!("{good}POINT_DATA 5\n")),
        "'box.vtk' line 14: POINT_DATA 5 does not match the 4 points"
    );
    assert_eq!(
        err(&format!("{good}CELL_DATA 2\n")),
        "'box.vtk' line 14: CELL_DATA 2 does not match the 1 cells"
    );
}

#[test]
fn truncated_binary_is_reported() {
    let m = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), [1, 1, 1]);
    let bytes = VtkWriter::new(&m.vertices, VtkCells::Tets(&m.elements))
        .to_bytes()
        .unwrap();
    for cut in [30, 100, 200, bytes.len() - 60] {
        let e = parse_vtk(&bytes[..cut], "cut.vtk").unwrap_err();
        assert!(
            matches!(
                e,
                VtkError::UnexpectedEof { .. } | VtkError::Expected { .. } | VtkError::Invalid { .. }
            ),
            "cut {cut}: {e}"
        );
    }
    let e = parse_vtk(&bytes[..200], "cut.vtk").unwrap_err().to_string();
    assert!(
        e.starts_with("'cut.vtk' line 6: unexpected end of file while reading POINTS (27 binary values need 216 bytes"),
        "{e}"
    );
}
