//! MikkTSpace tangents (the `bevy_mikktspace` crate) for meshes whose normal textures come without
//! tangents, in glTF's convention.
//!
//! MikkTSpace gives every triangle corner its own tangent; corners of one vertex whose tangents
//! differ (a seam in texture space, a mirrored half) become separate vertices, so that the
//! interpolated frame is the one the normal texture was baked in.

use glam::{Vec2, Vec3, Vec4};

/// One indexed triangle mesh's vertex attributes (coordinate sets and tangents: empty or one
/// per position).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Vertices {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Coordinate sets 0 and 1.
    pub uvs: [Vec<Vec2>; 2],
    pub tangents: Vec<Vec4>,
}

struct Corners<'a> {
    v: &'a Vertices,
    /// The coordinate set the tangents follow.
    uvs: &'a [Vec2],
    indices: &'a [u32],
    out: Vec<Vec4>,
}

impl bevy_mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.v.positions[self.indices[face * 3 + vert] as usize].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.v.normals[self.indices[face * 3 + vert] as usize].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs[self.indices[face * 3 + vert] as usize].to_array()
    }
    fn set_tangent(
        &mut self,
        tangent: Option<bevy_mikktspace::TangentSpace>,
        face: usize,
        vert: usize,
    ) {
        self.out[face * 3 + vert] = tangent.map_or(Vec4::ZERO, |t| Vec4::from(t.tangent_encoded()));
    }
}

/// Tangents for `v` (positions, normals and coordinate set `set`, one each per vertex) and
/// `indices` (three per triangle): the vertices split where corners of one vertex get different
/// tangents, the new indices, and in `tangents` the tangent with the bitangent's sign in glTF's
/// convention (`bitangent = cross(normal, tangent) * w`, texture coordinates with v running down
/// the image, hence MikkTSpace's sign negated). `None` when the attributes do not allow it
/// (missing or non-finite values, no triangle) or MikkTSpace fails.
pub(crate) fn generate(v: &Vertices, indices: &[u32], set: usize) -> Option<(Vertices, Vec<u32>)> {
    let n = v.positions.len();
    let uvs = v.uvs.get(set)?;
    let complete = v.normals.len() == n
        && uvs.len() == n
        && v.uvs.iter().all(|u| u.is_empty() || u.len() == n)
        && !indices.is_empty()
        && indices.len().is_multiple_of(3)
        && indices.iter().all(|&i| (i as usize) < n)
        && v.positions.iter().all(|p| p.is_finite())
        && v.normals.iter().all(|p| p.is_finite())
        && uvs.iter().all(|p| p.is_finite());
    if !complete {
        return None;
    }
    let mut corners = Corners { v, uvs, indices, out: vec![Vec4::ZERO; indices.len()] };
    bevy_mikktspace::generate_tangents(&mut corners).ok()?;
    // Weld corners that share a vertex and a tangent.
    let mut out = Vertices::default();
    let mut seen = std::collections::HashMap::new();
    let mut new_indices = Vec::with_capacity(indices.len());
    for (&i, t) in indices.iter().zip(&corners.out) {
        let t = if t.is_finite() { Vec4::new(t.x, t.y, t.z, -t.w) } else { Vec4::ZERO };
        let key = (i, t.to_array().map(f32::to_bits));
        let index = *seen.entry(key).or_insert_with(|| {
            let k = i as usize;
            out.positions.push(v.positions[k]);
            out.normals.push(v.normals[k]);
            for (welded, source) in out.uvs.iter_mut().zip(&v.uvs) {
                if !source.is_empty() {
                    welded.push(source[k]);
                }
            }
            out.tangents.push(t);
            out.positions.len() as u32 - 1
        });
        new_indices.push(index);
    }
    Some((out, new_indices))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad in the z = 0 plane facing +z with u along +x and v down the image (along -y):
    /// the tangent is +x and the bitangent cross(n, t) * w is +y (glTF's "green up").
    #[test]
    fn a_plain_quad_gets_x_tangents_and_a_positive_sign() {
        let v = Vertices {
            positions: vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            normals: vec![Vec3::Z; 4],
            uvs: [
                vec![
                    Vec2::new(0.0, 1.0),
                    Vec2::new(1.0, 1.0),
                    Vec2::new(1.0, 0.0),
                    Vec2::new(0.0, 0.0),
                ],
                vec![],
            ],
            ..Vertices::default()
        };
        let (out, indices) = generate(&v, &[0, 1, 2, 0, 2, 3], 0).unwrap();
        assert_eq!(out.positions.len(), 4, "one tangent per vertex: nothing to split");
        assert_eq!(indices.len(), 6);
        for t in &out.tangents {
            assert!((t.truncate() - Vec3::X).length() < 1e-5, "{t}");
            assert_eq!(t.w, 1.0);
        }
        // Mirrored in u: the tangent turns to -x and the sign flips, the bitangent stays +y.
        // Read through set 1, set 0 left as it was and carried along.
        let mirrored = Vertices {
            uvs: [v.uvs[0].clone(), v.uvs[0].iter().map(|t| Vec2::new(1.0 - t.x, t.y)).collect()],
            ..v.clone()
        };
        let (out, _) = generate(&mirrored, &[0, 1, 2, 0, 2, 3], 1).unwrap();
        assert_eq!(out.uvs[0], v.uvs[0]);
        for t in &out.tangents {
            assert!((t.truncate() + Vec3::X).length() < 1e-5, "{t}");
            assert!((Vec3::Z.cross(t.truncate()) * t.w - Vec3::Y).length() < 1e-5);
        }
        // Incomplete attributes give none.
        assert!(generate(&Vertices { normals: vec![], ..v.clone() }, &[0, 1, 2], 0).is_none());
        assert!(generate(&v, &[0, 1, 2], 1).is_none(), "no set 1");
    }
}
