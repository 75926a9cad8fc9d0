//! Splitting one large mesh into spatially compact parts, so that a model
//! stored as a few huge meshes still gives culling many objects to decide on.

use glam::Vec3;
use occlude_core::{Aabb, Mesh};

/// Splits `mesh` into parts of at most `max_triangles` triangles (0: never
/// split) by recursive median splits of triangle centroids along the longest
/// axis of their box. Deterministic: ties are broken by triangle order. Each
/// part keeps only the vertices it uses.
pub(crate) fn split(mesh: Mesh, max_triangles: usize) -> Vec<Mesh> {
    if max_triangles == 0 || mesh.triangle_count() <= max_triangles {
        return vec![mesh];
    }
    let centroids: Vec<Vec3> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| (mesh.positions[t[0] as usize] + mesh.positions[t[1] as usize] + mesh.positions[t[2] as usize]) / 3.0)
        .collect();
    let mut triangles: Vec<u32> = (0..centroids.len() as u32).collect();
    let mut groups = Vec::new();
    partition(&mut triangles, &centroids, max_triangles, &mut groups);
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    groups.into_iter().map(|group| extract(&mesh, group, &mut remap)).collect()
}

/// Splits `triangles` at the median centroid until every group has at most
/// `max` triangles, appending the groups to `out` in left-to-right order.
fn partition<'t>(triangles: &'t mut [u32], centroids: &[Vec3], max: usize, out: &mut Vec<&'t [u32]>) {
    if triangles.len() <= max {
        out.push(triangles);
        return;
    }
    let bounds = Aabb::from_points(triangles.iter().map(|&t| &centroids[t as usize]));
    let axis = bounds.extent().max_position();
    let mid = triangles.len() / 2;
    triangles.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]).then(a.cmp(&b))
    });
    let (low, high) = triangles.split_at_mut(mid);
    partition(low, centroids, max, out);
    partition(high, centroids, max, out);
}

/// The part of `mesh` made of `triangles`, with its own compact vertices.
/// `remap` (one entry per vertex of `mesh`, all `u32::MAX`) is left as found.
fn extract(mesh: &Mesh, triangles: &[u32], remap: &mut [u32]) -> Mesh {
    let mut used = Vec::new();
    let mut indices = Vec::with_capacity(triangles.len() * 3);
    for &t in triangles {
        for &v in &mesh.indices[t as usize * 3..t as usize * 3 + 3] {
            if remap[v as usize] == u32::MAX {
                remap[v as usize] = used.len() as u32;
                used.push(v);
            }
            indices.push(remap[v as usize]);
        }
    }
    let positions = used.iter().map(|&v| mesh.positions[v as usize]).collect();
    for &v in &used {
        remap[v as usize] = u32::MAX;
    }
    Mesh::new(positions, indices)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat grid of `n` x `n` quads (2 n² triangles) over `[0, n]²`.
    fn grid(n: u32) -> Mesh {
        let positions = (0..=n).flat_map(|z| (0..=n).map(move |x| Vec3::new(x as f32, 0.0, z as f32))).collect();
        let indices = (0..n)
            .flat_map(|z| (0..n).map(move |x| z * (n + 1) + x))
            .flat_map(|i| [i, i + n + 1, i + 1, i + 1, i + n + 1, i + n + 2])
            .collect();
        Mesh::new(positions, indices)
    }

    #[test]
    fn large_mesh_splits_into_compact_parts_keeping_every_triangle() {
        let mesh = grid(20);
        let parts = split(mesh.clone(), 100);
        assert_eq!(parts.len(), 8, "800 triangles halve three times down to 100");
        assert_eq!(parts.iter().map(Mesh::triangle_count).sum::<usize>(), 800);
        for part in &parts {
            assert!(part.triangle_count() <= 100);
            assert!(part.positions.len() < mesh.positions.len() / 4, "a part keeps only its own vertices");
            assert!(part.indices.iter().all(|&i| (i as usize) < part.positions.len()));
            assert!(part.bounds.extent().x <= 10.0 && part.bounds.extent().z <= 10.0, "parts are compact");
        }
        let area: f32 = parts.iter().map(|p| p.bounds.extent().x * p.bounds.extent().z).sum();
        assert!((area - 400.0).abs() < 1e-3, "parts tile the grid without overlap: {area}");
    }

    #[test]
    fn zero_or_a_large_limit_never_splits() {
        assert_eq!(split(grid(4), 0).len(), 1);
        assert_eq!(split(grid(4), 32).len(), 1);
        assert_eq!(split(grid(4), 31).len(), 2);
    }
}
