//! Mesh file loaders: Wavefront OBJ, STL, legacy VTK and Gmsh `.msh` 4.1 (ASCII).
//!
//! [`load_mesh`] picks the loader from the file extension (case-insensitive) and returns a
//! [`LoadedMesh`] with positions, triangles and tets; [`load_triangle_mesh`] and
//! [`load_tet_mesh`] return a single-kind [`Mesh`] with unused vertices removed. Stark's own
//! loaders are `load_obj` (tinyobjloader, one mesh per OBJ shape, triangles only) and
//! `load_vtk<N>` (`stark/src/utils/mesh_utils.h`); this module adds STL and Gmsh.
//!
//! Positions from OBJ files are read as `f64` (tobj's `use_f64` feature), STL stores `f32`.
//! Merged OBJ and all STL meshes are welded with [`merge_by_distance`] at tolerance zero
//! (exactly equal positions become one vertex; triangles that become degenerate or duplicate
//! are dropped).

use std::collections::HashMap;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use crate::error::StarkError;
use crate::geometry::mesh::{merge_by_distance, MeshError};
use crate::io::vtk::{read_vtk, VtkError};
use crate::presets::meshes::Mesh;

/// Errors of the mesh loaders; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum MeshFileError {
    /// The file does not exist.
    #[error("file '{}' not found", path.display())]
    NotFound {
        /// The path as given.
        path: PathBuf,
    },
    /// [`load_mesh`] does not know the extension.
    #[error("unknown mesh file extension `{extension}` in '{}' (expected .obj, .stl, .dae, .vtk, .msh)", path.display())]
    UnknownExtension {
        /// The path as given.
        path: PathBuf,
        /// The extension with its dot, or an empty string if there is none.
        extension: String,
    },
    /// Reading the file failed.
    #[error("cannot read '{}': {source}", path.display())]
    Io {
        /// The path as given.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// tobj rejected the OBJ file.
    #[error("'{}': cannot parse OBJ: {source}", path.display())]
    Obj {
        /// The path as given.
        path: PathBuf,
        /// tobj's error.
        source: tobj::LoadError,
    },
    /// stl_io rejected the STL file.
    #[error("'{}': cannot parse STL: {source}", path.display())]
    Stl {
        /// The path as given.
        path: PathBuf,
        /// stl_io's error.
        source: io::Error,
    },
    /// mesh-loader rejected the COLLADA file.
    #[error("'{}': cannot parse COLLADA: {source}", path.display())]
    Collada {
        /// The path as given.
        path: PathBuf,
        /// mesh-loader's error.
        source: io::Error,
    },
    /// The VTK reader failed (its message names the file and line).
    #[error(transparent)]
    Vtk(#[from] VtkError),
    /// The Gmsh file does not follow the format.
    #[error("'{}' line {line}: {message}", path.display())]
    Msh {
        /// The path as given.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The loaded connectivity is invalid.
    #[error("'{}': {source}", path.display())]
    Mesh {
        /// The path as given.
        path: PathBuf,
        /// The problem found.
        source: MeshError,
    },
    /// The file holds no elements of the requested kind.
    #[error("'{}' contains no {what}", path.display())]
    NoElements {
        /// The path as given.
        path: PathBuf,
        /// "triangles" or "tetrahedra".
        what: &'static str,
    },
}

/// Everything a loader found: positions plus triangles and/or tets indexing them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LoadedMesh {
    /// Vertex positions in file units (usually metres).
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles (OBJ/STL faces, VTK triangle cells, Gmsh type-2 elements).
    pub triangles: Vec<[usize; 3]>,
    /// Tetrahedra (VTK tetra cells, Gmsh type-4 elements).
    pub tets: Vec<[usize; 4]>,
}

/// Keeps only the vertices used by `elements`, in their original relative order.
fn compact<const K: usize>(vertices: &[Vector3<f64>], elements: &[[usize; K]]) -> Mesh<K> {
    let mut used = vec![false; vertices.len()];
    elements.iter().flatten().for_each(|&i| used[i] = true);
    let mut old_to_new = vec![usize::MAX; vertices.len()];
    let mut kept = Vec::new();
    for (i, v) in vertices.iter().enumerate() {
        if used[i] {
            old_to_new[i] = kept.len();
            kept.push(*v);
        }
    }
    Mesh {
        vertices: kept,
        elements: elements.iter().map(|e| e.map(|i| old_to_new[i])).collect(),
    }
}

impl From<MeshFileError> for StarkError {
    fn from(e: MeshFileError) -> Self {
        StarkError::Mesh(Box::new(e))
    }
}

fn check_exists(path: &Path) -> Result<(), MeshFileError> {
    if path.is_file() {
        Ok(())
    } else {
        Err(MeshFileError::NotFound { path: path.to_owned() })
    }
}

fn read_to_bytes(path: &Path) -> Result<Vec<u8>, MeshFileError> {
    fs::read(path).map_err(|source| {
        if source.kind() == io::ErrorKind::NotFound {
            MeshFileError::NotFound { path: path.to_owned() }
        } else {
            MeshFileError::Io {
                path: path.to_owned(),
                source,
            }
        }
    })
}

/// Loads a mesh, choosing the format from the extension: `.obj` ([`load_obj`]), `.stl`
/// ([`load_stl`]), `.vtk` ([`load_vtk_mesh`]) or `.msh` ([`load_msh`]).
///
/// # Errors
/// [`MeshFileError::UnknownExtension`], [`MeshFileError::NotFound`], or the loader's error.
pub fn load_mesh(path: impl AsRef<Path>) -> Result<LoadedMesh, MeshFileError> {
    let path = path.as_ref();
    let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("obj") => load_obj(path).map(|m| LoadedMesh {
            vertices: m.vertices,
            triangles: m.elements,
            tets: Vec::new(),
        }),
        Some("stl") => load_stl(path).map(|m| LoadedMesh {
            vertices: m.vertices,
            triangles: m.elements,
            tets: Vec::new(),
        }),
        Some("dae") => load_collada(path).map(|m| LoadedMesh {
            vertices: m.vertices,
            triangles: m.elements,
            tets: Vec::new(),
        }),
        Some("vtk") => load_vtk_mesh(path),
        Some("msh") => load_msh(path),
        _ => Err(MeshFileError::UnknownExtension {
            path: path.to_owned(),
            extension: path
                .extension()
                .map(|e| format!(".{}", e.to_string_lossy()))
                .unwrap_or_default(),
        }),
    }
}

/// Loads the triangles of any supported file ([`load_mesh`]), dropping unused vertices
/// (kept vertices stay in file order).
///
/// # Errors
/// As [`load_mesh`], plus [`MeshFileError::NoElements`] if there is no triangle.
pub fn load_triangle_mesh(path: impl AsRef<Path>) -> Result<Mesh<3>, MeshFileError> {
    let path = path.as_ref();
    let loaded = load_mesh(path)?;
    if loaded.triangles.is_empty() {
        return Err(MeshFileError::NoElements {
            path: path.to_owned(),
            what: "triangles",
        });
    }
    Ok(compact(&loaded.vertices, &loaded.triangles))
}

/// Loads the tets of a `.vtk` or `.msh` file ([`load_mesh`]), dropping vertices no tet uses
/// (kept vertices stay in file order). Orientation is not changed; see
/// [`crate::geometry::mesh::check_tet_volumes`] and
/// [`crate::geometry::mesh::fix_tet_orientation`].
///
/// # Errors
/// As [`load_mesh`], plus [`MeshFileError::NoElements`] if there is no tet.
pub fn load_tet_mesh(path: impl AsRef<Path>) -> Result<Mesh<4>, MeshFileError> {
    let path = path.as_ref();
    let loaded = load_mesh(path)?;
    if loaded.tets.is_empty() {
        return Err(MeshFileError::NoElements {
            path: path.to_owned(),
            what: "tetrahedra",
        });
    }
    Ok(compact(&loaded.vertices, &loaded.tets))
}

fn obj_models(path: &Path) -> Result<Vec<tobj::Model>, MeshFileError> {
    check_exists(path)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|source| match source {
        tobj::LoadError::OpenFileFailed => MeshFileError::NotFound { path: path.to_owned() },
        source => MeshFileError::Obj {
            path: path.to_owned(),
            source,
        },
    })?;
    Ok(models)
}

fn obj_model_mesh(model: &tobj::Model) -> Mesh<3> {
    let m = &model.mesh;
    Mesh {
        vertices: m
            .positions
            .chunks_exact(3)
            .map(|p| Vector3::new(p[0], p[1], p[2]))
            .collect(),
        elements: m
            .indices
            .chunks_exact(3)
            .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
            .collect(),
    }
}

/// Loads every shape (`o`/`g` group) of an OBJ file as its own triangle mesh, named as in
/// the file: the counterpart of Stark's `load_obj`, which returns one mesh per shape with
/// the shape's vertices re-indexed compactly. Polygons are triangulated as fans; points and
/// lines are ignored; materials are ignored.
///
/// # Errors
/// [`MeshFileError::NotFound`] or [`MeshFileError::Obj`].
pub fn load_obj_shapes(path: impl AsRef<Path>) -> Result<Vec<(String, Mesh<3>)>, MeshFileError> {
    Ok(obj_models(path.as_ref())?
        .iter()
        .map(|model| (model.name.clone(), obj_model_mesh(model)))
        .collect())
}

/// Parses OBJ text (an asset compiled into the program) into one triangle mesh: its shapes
/// merged in file order, polygons triangulated as fans, not welded (two meshes of the same
/// faces, such as a rest shape and a deformed one, keep corresponding vertex numbers).
/// `name` stands for the path in errors.
///
/// # Errors
/// [`MeshFileError::Obj`].
pub fn parse_obj(text: &str, name: &str) -> Result<Mesh<3>, MeshFileError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = io::BufReader::new(text.as_bytes());
    let (models, _materials) =
        tobj::load_obj_buf(&mut reader, &options, |_| Ok(Default::default())).map_err(|source| MeshFileError::Obj {
            path: PathBuf::from(name),
            source,
        })?;
    let mut all = Mesh::<3>::default();
    for model in &models {
        let m = obj_model_mesh(model);
        let offset = all.vertices.len();
        all.vertices.extend(m.vertices);
        all.elements.extend(m.elements.iter().map(|t| t.map(|i| i + offset)));
    }
    Ok(all)
}

/// Loads all shapes of an OBJ file merged into one triangle mesh; vertices at exactly the
/// same position are welded (shapes that share OBJ vertices become connected again).
///
/// # Errors
/// [`MeshFileError::NotFound`] or [`MeshFileError::Obj`].
pub fn load_obj(path: impl AsRef<Path>) -> Result<Mesh<3>, MeshFileError> {
    let path = path.as_ref();
    let mut all = Mesh::<3>::default();
    for model in obj_models(path)? {
        let m = obj_model_mesh(&model);
        let offset = all.vertices.len();
        all.vertices.extend(m.vertices);
        all.elements.extend(m.elements.iter().map(|t| t.map(|i| i + offset)));
    }
    weld(path, all)
}

fn weld(path: &Path, mesh: Mesh<3>) -> Result<Mesh<3>, MeshFileError> {
    let merged = merge_by_distance(&mesh.vertices, &mesh.elements, 0.0).map_err(|source| MeshFileError::Mesh {
        path: path.to_owned(),
        source,
    })?;
    Ok(Mesh {
        vertices: merged.vertices,
        elements: merged.elements,
    })
}

/// Loads an ASCII or binary STL file; duplicated corner positions (STL stores every triangle
/// separately) are merged into shared vertices.
///
/// # Errors
/// [`MeshFileError::NotFound`], [`MeshFileError::Io`] or [`MeshFileError::Stl`].
pub fn load_stl(path: impl AsRef<Path>) -> Result<Mesh<3>, MeshFileError> {
    let path = path.as_ref();
    parse_stl(&read_to_bytes(path)?, path)
}

/// [`load_stl`] of a file's bytes (e.g. compiled into a program); `path` names it in errors.
///
/// # Errors
/// [`MeshFileError::Stl`].
pub fn parse_stl(bytes: &[u8], path: &Path) -> Result<Mesh<3>, MeshFileError> {
    let indexed = stl_io::read_stl(&mut io::Cursor::new(bytes)).map_err(|source| MeshFileError::Stl {
        path: path.to_owned(),
        source,
    })?;
    let mesh = Mesh {
        vertices: indexed
            .vertices
            .iter()
            .map(|v| Vector3::new(v.0[0] as f64, v.0[1] as f64, v.0[2] as f64))
            .collect(),
        elements: indexed.faces.iter().map(|f| f.vertices).collect(),
    };
    weld(path, mesh)
}

/// Loads the triangles of every mesh of a COLLADA (`.dae`) file with mesh-loader (node
/// transforms and the `<unit>` scale applied, so positions are in metres); the meshes are merged
/// and coincident corners (COLLADA exporters often write one vertex per triangle corner) welded
/// into shared vertices. `up_axis` is not applied (URDF meshes are Z up).
///
/// # Errors
/// [`MeshFileError::NotFound`], [`MeshFileError::Io`] or [`MeshFileError::Collada`].
pub fn load_collada(path: impl AsRef<Path>) -> Result<Mesh<3>, MeshFileError> {
    let path = path.as_ref();
    let bytes = read_to_bytes(path)?;
    let scene = mesh_loader::Loader::default()
        .load_collada_from_slice(&bytes, path)
        .map_err(|source| MeshFileError::Collada {
            path: path.to_owned(),
            source,
        })?;
    let mut mesh = Mesh {
        vertices: Vec::new(),
        elements: Vec::new(),
    };
    for m in &scene.meshes {
        let base = mesh.vertices.len();
        mesh.vertices.extend(
            m.vertices
                .iter()
                .map(|v| Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64)),
        );
        mesh.elements
            .extend(m.faces.iter().map(|f| f.map(|i| base + i as usize)));
    }
    if mesh.elements.is_empty() {
        return Err(MeshFileError::NoElements {
            path: path.to_owned(),
            what: "triangles",
        });
    }
    weld(path, mesh)
}

/// Loads the triangles and tets of a legacy VTK UNSTRUCTURED_GRID file (see
/// [`crate::io::vtk::read_vtk`]; vertex and line cells are ignored). Stark's `load_vtk<N>`.
///
/// # Errors
/// [`MeshFileError::Vtk`].
pub fn load_vtk_mesh(path: impl AsRef<Path>) -> Result<LoadedMesh, MeshFileError> {
    let vtk = read_vtk(path)?;
    Ok(LoadedMesh {
        vertices: vtk.points,
        triangles: vtk.triangles,
        tets: vtk.tets,
    })
}

/// Loads a Gmsh `.msh` file in format 4.1 ASCII: all nodes (in file order) plus the 3-node
/// triangles (element type 2) and 4-node tetrahedra (type 4). Points (15) and lines (1) are
/// skipped; other element types are an error. Unknown sections (`$Entities`,
/// `$PhysicalNames`, ...) are skipped.
///
/// # Errors
/// [`MeshFileError::NotFound`], [`MeshFileError::Io`] or [`MeshFileError::Msh`] naming the
/// line, e.g. for a binary or version 2.2 file.
pub fn load_msh(path: impl AsRef<Path>) -> Result<LoadedMesh, MeshFileError> {
    let path = path.as_ref();
    let bytes = read_to_bytes(path)?;
    parse_msh(&String::from_utf8_lossy(&bytes), path)
}

/// Parses the text of a Gmsh 4.1 ASCII file; `path` is used in errors. See [`load_msh`].
///
/// # Errors
/// [`MeshFileError::Msh`].
pub fn parse_msh(text: &str, path: &Path) -> Result<LoadedMesh, MeshFileError> {
    MshParser {
        tokens: tokenize(text),
        next: 0,
        path,
        last_line: text.lines().count().max(1),
    }
    .parse()
}

/// Whitespace-separated tokens with their 1-based line numbers.
fn tokenize(text: &str) -> Vec<(usize, &str)> {
    text.lines()
        .enumerate()
        .flat_map(|(i, line)| line.split_whitespace().map(move |t| (i + 1, t)))
        .collect()
}

struct MshParser<'a> {
    tokens: Vec<(usize, &'a str)>,
    next: usize,
    path: &'a Path,
    last_line: usize,
}

impl<'a> MshParser<'a> {
    fn error(&self, line: usize, message: impl Into<String>) -> MeshFileError {
        MeshFileError::Msh {
            path: self.path.to_owned(),
            line,
            message: message.into(),
        }
    }

    fn token(&mut self, what: &str) -> Result<(usize, &'a str), MeshFileError> {
        let t = self
            .tokens
            .get(self.next)
            .copied()
            .ok_or_else(|| self.error(self.last_line, format!("unexpected end of file, expected {what}")))?;
        self.next += 1;
        Ok(t)
    }

    fn number<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, MeshFileError> {
        let (line, t) = self.token(what)?;
        t.parse()
            .map_err(|_| self.error(line, format!("expected {what}, found '{t}'")))
    }

    fn expect(&mut self, keyword: &str) -> Result<(), MeshFileError> {
        let (line, t) = self.token(keyword)?;
        if t == keyword {
            Ok(())
        } else {
            Err(self.error(line, format!("expected {keyword}, found '{t}'")))
        }
    }

    fn parse(mut self) -> Result<LoadedMesh, MeshFileError> {
        let mut mesh = LoadedMesh::default();
        let mut node_index: HashMap<usize, usize> = HashMap::new();
        let mut seen_format = false;
        let mut seen_nodes = false;
        while self.next < self.tokens.len() {
            let (line, section) = self.token("a section")?;
            match section {
                "$MeshFormat" => {
                    let (vline, version) = self.token("the format version")?;
                    if version != "4.1" {
                        return Err(self.error(
                            vline,
                            format!(
                                "Gmsh format version {version} is not supported (expected 4.1; re-export with `gmsh -format msh41`)"
                            ),
                        ));
                    }
                    let (fline, file_type) = self.token("the file type")?;
                    if file_type != "0" {
                        return Err(self.error(
                            fline,
                            "binary .msh files are not supported (expected ASCII, file type 0)",
                        ));
                    }
                    let _data_size: usize = self.number("the data size")?;
                    self.expect("$EndMeshFormat")?;
                    seen_format = true;
                }
                "$Nodes" => {
                    if !seen_format {
                        return Err(self.error(line, "expected $MeshFormat before $Nodes"));
                    }
                    self.nodes(&mut mesh.vertices, &mut node_index)?;
                    seen_nodes = true;
                }
                "$Elements" => {
                    if !seen_nodes {
                        return Err(self.error(line, "expected $Nodes before $Elements"));
                    }
                    self.elements(&mut mesh, &node_index)?;
                }
                s if s.starts_with('$') && !s.starts_with("$End") => {
                    let end = format!("$End{}", &s[1..]);
                    loop {
                        let (_, t) = self.token(&end)?;
                        if t == end {
                            break;
                        }
                    }
                }
                other => {
                    return Err(self.error(line, format!("expected a section such as $MeshFormat, found '{other}'")))
                }
            }
        }
        if !seen_format {
            return Err(self.error(1, "expected $MeshFormat, the file has none"));
        }
        Ok(mesh)
    }

    fn nodes(
        &mut self,
        vertices: &mut Vec<Vector3<f64>>,
        node_index: &mut HashMap<usize, usize>,
    ) -> Result<(), MeshFileError> {
        let n_blocks: usize = self.number("the number of node blocks")?;
        let n_nodes: usize = self.number("the number of nodes")?;
        let _min: usize = self.number("the minimum node tag")?;
        let _max: usize = self.number("the maximum node tag")?;
        vertices.reserve(n_nodes.min(1 << 24));
        for _ in 0..n_blocks {
            let entity_dim: usize = self.number("the entity dimension")?;
            let _entity: i64 = self.number("the entity tag")?;
            let parametric: u8 = self.number("the parametric flag")?;
            let n: usize = self.number("the number of nodes in the block")?;
            let mut tags = Vec::with_capacity(n.min(1 << 24));
            for _ in 0..n {
                let line = self.tokens.get(self.next).map_or(self.last_line, |t| t.0);
                let tag: usize = self.number("a node tag")?;
                if node_index.insert(tag, vertices.len() + tags.len()).is_some() {
                    return Err(self.error(line, format!("node tag {tag} is defined twice")));
                }
                tags.push(tag);
            }
            for _ in 0..n {
                let x: f64 = self.number("a node x coordinate")?;
                let y: f64 = self.number("a node y coordinate")?;
                let z: f64 = self.number("a node z coordinate")?;
                if parametric == 1 {
                    for _ in 0..entity_dim {
                        let _u: f64 = self.number("a parametric coordinate")?;
                    }
                }
                vertices.push(Vector3::new(x, y, z));
            }
        }
        if vertices.len() != n_nodes {
            let line = self.tokens.get(self.next).map_or(self.last_line, |t| t.0);
            return Err(self.error(
                line,
                format!("$Nodes declares {n_nodes} nodes but its blocks hold {}", vertices.len()),
            ));
        }
        self.expect("$EndNodes")
    }

    fn elements(&mut self, mesh: &mut LoadedMesh, node_index: &HashMap<usize, usize>) -> Result<(), MeshFileError> {
        let n_blocks: usize = self.number("the number of element blocks")?;
        let _n_elements: usize = self.number("the number of elements")?;
        let _min: usize = self.number("the minimum element tag")?;
        let _max: usize = self.number("the maximum element tag")?;
        for _ in 0..n_blocks {
            let _dim: usize = self.number("the entity dimension")?;
            let _entity: i64 = self.number("the entity tag")?;
            let (type_line, _) = self.tokens.get(self.next).copied().unwrap_or((self.last_line, ""));
            let element_type: u32 = self.number("the element type")?;
            let n: usize = self.number("the number of elements in the block")?;
            let n_nodes = match element_type {
                15 => 1,
                1 => 2,
                2 => 3,
                4 => 4,
                other => {
                    return Err(self.error(
                        type_line,
                        format!(
                            "Gmsh element type {other} ({}) is not supported (expected 2: triangle, 4: tetrahedron; 1 and 15 are skipped)",
                            msh_element_name(other)
                        ),
                    ))
                }
            };
            for _ in 0..n {
                let _tag: usize = self.number("an element tag")?;
                let mut nodes = [0usize; 4];
                for node in nodes.iter_mut().take(n_nodes) {
                    let (line, _) = self.tokens.get(self.next).copied().unwrap_or((self.last_line, ""));
                    let tag: usize = self.number("a node tag")?;
                    *node = *node_index.get(&tag).ok_or_else(|| {
                        self.error(
                            line,
                            format!("element references node {tag}, which $Nodes does not define"),
                        )
                    })?;
                }
                match element_type {
                    2 => mesh.triangles.push([nodes[0], nodes[1], nodes[2]]),
                    4 => mesh.tets.push(nodes),
                    _ => {}
                }
            }
        }
        self.expect("$EndElements")
    }
}

fn msh_element_name(element_type: u32) -> &'static str {
    match element_type {
        3 => "4-node quadrangle",
        5 => "8-node hexahedron",
        6 => "6-node prism",
        7 => "5-node pyramid",
        8 => "3-node line",
        9 => "6-node triangle",
        10 => "9-node quadrangle",
        11 => "10-node tetrahedron",
        _ => "unknown",
    }
}

#[cfg(test)]
mod tests;
