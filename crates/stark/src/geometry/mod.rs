//! Geometric and topological mesh utilities.

pub mod mesh;

pub use mesh::{
    bounding_box, center, check_indices, check_tet_volumes, edges_from_simplices, edges_from_tets,
    edges_from_triangles, find_hinges, find_surface, find_surface_triangles, fix_tet_orientation,
    lumped_masses_from_segments, lumped_masses_from_tets, lumped_masses_from_triangles,
    merge_by_distance, mirror, perimeter_edges, reduce_connectivity, rotate, rotate_about,
    rotate_deg, scale, scale_xyz, segment_length, segment_lengths, sharp_edges, tet_signed_volume,
    tet_signed_volumes, total_tet_volume, translate, triangle_area, triangle_areas,
    triangle_normal, vertex_normals, MergedMesh, MeshError,
};
