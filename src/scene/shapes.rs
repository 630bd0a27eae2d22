//! Shapes generated in code, for built-in scenes and tests.

use glam::Vec3;

/// The triangles of an icosphere of radius 1 about the origin: the icosahedron with each
/// face split in four `levels` times (20 · 4^levels triangles), every vertex on the
/// sphere, wound counter-clockwise seen from outside (geometric normals point out).
pub fn icosphere(levels: u32) -> Vec<[Vec3; 3]> {
    let g = (1.0 + 5.0f32.sqrt()) * 0.5;
    let v = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ]
    .map(|p| Vec3::from_array(p).normalize());
    let faces: [[usize; 3]; 20] = [
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
    let mut tris: Vec<[Vec3; 3]> = faces.iter().map(|f| f.map(|i| v[i])).collect();
    for _ in 0..levels {
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    (a + b).normalize(),
                    (b + c).normalize(),
                    (c + a).normalize(),
                );
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    for t in &mut tris {
        let centroid = (t[0] + t[1] + t[2]) / 3.0;
        if (t[1] - t[0]).cross(t[2] - t[0]).dot(centroid) < 0.0 {
            t.swap(1, 2);
        }
    }
    tris
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_is_closed_outward_and_on_the_sphere() {
        for levels in 0..3 {
            let tris = icosphere(levels);
            assert_eq!(tris.len(), 20 * 4usize.pow(levels));
            for t in &tris {
                let n = (t[1] - t[0]).cross(t[2] - t[0]);
                assert!(n.dot(t[0] + t[1] + t[2]) > 0.0);
                for p in t {
                    assert!((p.length() - 1.0).abs() < 1e-6);
                }
            }
            // Closed: the area-weighted normals cancel.
            let sum: Vec3 = tris.iter().map(|t| (t[1] - t[0]).cross(t[2] - t[0])).sum();
            assert!(sum.length() < 1e-4, "{sum}");
        }
    }
}
