//! Walking the default scene's node hierarchy: world transforms, and the
//! meshes, cameras and punctual lights hanging off each node.

use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json::extensions::scene::khr_lights_punctual::Type as LightType;
use gltf::json::validation::Checked;
use gltf::mesh::Mode;

use super::accessor::{read_indices, read_vec};
use super::source::Source;
use crate::scene::{Camera, PunctualLight, Triangle, TriangleShading};
use crate::texture::TriangleUv;

/// The most triangles one scene may hold (2^24, about 16.8 million, or
/// 2.4 GB of triangle and shading data): a guard against documents that
/// instance a mesh absurdly often, checked before anything is allocated.
pub const MAX_TRIANGLES: u64 = 1 << 24;

/// What the traversal collects, in depth-first pre-order of the nodes.
#[derive(Default)]
pub struct Collected {
    pub triangles: Vec<Triangle>,
    pub shading: Vec<TriangleShading>,
    pub cameras: Vec<Camera>,
    pub lights: Vec<PunctualLight>,
    /// Per-triangle texture coordinates (only when asked for).
    pub uvs: Vec<TriangleUv>,
    /// Some primitive had no material: the caller appends the glTF default
    /// material at index `default_material`.
    pub uses_default_material: bool,
}

/// Walk `scene_index`'s nodes depth first, children in order. Each node is
/// visited at most once: glTF requires the node graph to be a forest, and a
/// node reached twice (a cycle, or a child shared by two parents) is an error
/// rather than a hang or an exponential blow-up.
pub fn collect(
    src: &Source,
    scene_index: usize,
    default_material: u32,
    want_uvs: bool,
    warnings: &mut Vec<String>,
) -> Result<Collected, String> {
    let root = src.doc.as_json();
    let scene = root
        .scenes
        .get(scene_index)
        .ok_or_else(|| format!("scene {scene_index} does not exist"))?;
    let meshes: Vec<gltf::Mesh> = src.doc.meshes().collect();
    let mut visited = vec![false; root.nodes.len()];
    let mut out = Collected::default();
    let mut instances: Vec<(&gltf::Mesh, Mat4, String)> = Vec::new();
    let mut skipped = Skipped::default();
    // Explicit stack: a 100,000-deep chain of nodes must not overflow the
    // call stack.
    let mut stack: Vec<(usize, Mat4)> = scene
        .nodes
        .iter()
        .rev()
        .map(|n| (n.value(), Mat4::IDENTITY))
        .collect();
    while let Some((i, parent)) = stack.pop() {
        let node = root
            .nodes
            .get(i)
            .ok_or_else(|| format!("node {i} does not exist"))?;
        let label = match &node.name {
            Some(name) => format!("node {i} ('{name}')"),
            None => format!("node {i}"),
        };
        if std::mem::replace(&mut visited[i], true) {
            return Err(format!(
                "{label} is reached twice in scene {scene_index} (a cycle or a shared child in the node graph)"
            ));
        }
        let local = local_transform(node).map_err(|e| format!("{label}: {e}"))?;
        let world = parent * local;
        if !world.is_finite() {
            return Err(format!(
                "{label}: world transform overflows to a non-finite value"
            ));
        }
        if node.skin.is_some() {
            skipped.skins += 1;
        }
        if let Some(m) = node.mesh {
            let mesh = meshes
                .get(m.value())
                .ok_or_else(|| format!("{label}: mesh {} does not exist", m.value()))?;
            instances.push((mesh, world, label.clone()));
        }
        if let Some(cam) = node.camera {
            let mut c = camera(src, cam.value(), world).map_err(|e| format!("{label}: {e}"))?;
            c.node_name = node.name.clone();
            out.cameras.push(c);
        }
        if let Some(light) = light_index(src, i) {
            out.lights
                .push(punctual(src, light, world).map_err(|e| format!("{label}: {e}"))?);
        }
        for child in node.children.iter().flatten().rev() {
            stack.push((child.value(), world));
        }
    }
    // Count before generating anything: instancing can multiply a small
    // file into billions of triangles.
    let mut total = 0u64;
    for (mesh, _, _) in &instances {
        total = total.saturating_add(declared_triangles(root, mesh));
    }
    if total > MAX_TRIANGLES {
        return Err(format!(
            "the scene would hold {total} triangles, more than glint's limit of {MAX_TRIANGLES}"
        ));
    }
    for (mesh, world, label) in instances {
        add_mesh(
            src,
            mesh,
            world,
            default_material,
            want_uvs,
            &mut out,
            &mut skipped,
        )
        .map_err(|e| format!("{label}: {e}"))?;
    }
    skipped.warn(warnings);
    Ok(out)
}

/// What the traversal skipped, counted so each kind is one warning.
#[derive(Default)]
struct Skipped {
    points_lines: usize,
    skins: usize,
    morphs: usize,
}

impl Skipped {
    fn warn(&self, warnings: &mut Vec<String>) {
        if self.points_lines > 0 {
            warnings.push(format!(
                "{} point or line primitive(s) skipped (glint renders triangles)",
                self.points_lines
            ));
        }
        if self.skins > 0 {
            warnings.push(format!(
                "{} skinned node(s) rendered in the rest pose (skins are not supported)",
                self.skins
            ));
        }
        if self.morphs > 0 {
            warnings.push(format!(
                "{} primitive(s) with morph targets rendered in the rest pose (morph targets are not supported)",
                self.morphs
            ));
        }
    }
}

/// A node's local matrix from its raw JSON fields (not the `gltf` wrapper,
/// which decomposes matrices and would hide what was written).
fn local_transform(json: &gltf::json::Node) -> Result<Mat4, String> {
    if let Some(m) = json.matrix {
        if m.iter().any(|x| !x.is_finite()) {
            return Err(format!("matrix has a non-finite value: {m:?}"));
        }
        let mat = Mat4::from_cols_array(&m);
        // glTF node matrices are affine (spec 3.5.3): a projective bottom row
        // would be silently dropped by point transforms, so refuse it.
        if mat.row(3) != Vec4::W {
            return Err(format!("matrix is not affine (last row {})", mat.row(3)));
        }
        return Ok(mat);
    }
    let t = Vec3::from(json.translation.unwrap_or([0.0; 3]));
    let s = Vec3::from(json.scale.unwrap_or([1.0; 3]));
    let r = Vec4::from(json.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0));
    if !(t.is_finite() && s.is_finite() && r.is_finite()) {
        return Err(format!(
            "translation/rotation/scale has a non-finite value: {t}, {r}, {s}"
        ));
    }
    if r.length() < 1e-6 {
        return Err(format!("rotation quaternion {r} has zero length"));
    }
    // Unit quaternions are required; renormalise harmless rounding.
    let q = Quat::from_vec4(r.normalize());
    Ok(Mat4::from_scale_rotation_translation(s, q, t))
}

/// The matrix that carries normals: the inverse transpose of the linear
/// part, computed as the cofactor matrix (columns c1 x c2, c2 x c0, c0 x c1)
/// times sign(det), which is defined even for singular transforms. Only
/// directions matter, since normals are renormalised.
fn normal_matrix(m: Mat3) -> Mat3 {
    let cof = Mat3::from_cols(
        m.y_axis.cross(m.z_axis),
        m.z_axis.cross(m.x_axis),
        m.x_axis.cross(m.y_axis),
    );
    if m.determinant() < 0.0 { -cof } else { cof }
}

/// A primitive's vertex data as read (and checked) from its accessors.
struct PrimData {
    positions: Vec<[f32; 3]>,
    normals: Option<Vec<[f32; 3]>>,
    tangents: Option<Vec<[f32; 4]>>,
    /// TEXCOORD_0 (read when textures are used or for dP/du tangents) and
    /// TEXCOORD_1 (when textures are used).
    uvs: Option<Vec<[f32; 2]>>,
    uvs1: Option<Vec<[f32; 2]>>,
    indices: Option<Vec<u32>>,
}

fn read_primitive(
    src: &Source,
    prim: &gltf::Primitive,
    want_uvs: bool,
) -> Result<PrimData, String> {
    let root = src.doc.as_json();
    let pos_acc = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| "has no POSITION attribute".to_string())?;
    let positions = read_vec::<3>(root, &src.buffers, pos_acc.index())?;
    if let Some(k) = positions.iter().position(|p| !Vec3::from(*p).is_finite()) {
        return Err(format!("POSITION {k} is not finite: {:?}", positions[k]));
    }
    let n_verts = positions.len();
    let attr = |sem: gltf::Semantic| -> Option<usize> { prim.get(&sem).map(|a| a.index()) };
    let same_count = |name: &str, len: usize| -> Result<(), String> {
        if len == n_verts {
            Ok(())
        } else {
            Err(format!(
                "{name} has {len} elements but POSITION has {n_verts}"
            ))
        }
    };
    let normals = match attr(gltf::Semantic::Normals) {
        Some(a) => {
            let v = read_vec::<3>(root, &src.buffers, a)?;
            same_count("NORMAL", v.len())?;
            if let Some(k) = v.iter().position(|n| !Vec3::from(*n).is_finite()) {
                return Err(format!("NORMAL {k} is not finite: {:?}", v[k]));
            }
            Some(v)
        }
        None => None,
    };
    let tangents = match attr(gltf::Semantic::Tangents) {
        Some(a) => {
            let v = read_vec::<4>(root, &src.buffers, a)?;
            same_count("TANGENT", v.len())?;
            Some(v)
        }
        None => None,
    };
    let read_uv = |set: u32| -> Result<Option<Vec<[f32; 2]>>, String> {
        match attr(gltf::Semantic::TexCoords(set)) {
            Some(a) => {
                let v = read_vec::<2>(root, &src.buffers, a)?;
                same_count(&format!("TEXCOORD_{set}"), v.len())?;
                Ok(Some(v))
            }
            None => Ok(None),
        }
    };
    let uvs = if tangents.is_none() || want_uvs {
        read_uv(0)?
    } else {
        None
    };
    let uvs1 = if want_uvs { read_uv(1)? } else { None };
    let indices = match prim.indices() {
        Some(a) => Some(read_indices(root, &src.buffers, a.index())?),
        None => None,
    };
    Ok(PrimData {
        positions,
        normals,
        tangents,
        uvs,
        uvs1,
        indices,
    })
}

/// Where a mesh instance goes: its node's world transform and what
/// follows from it for normals and winding.
struct Placement {
    world: Mat4,
    linear: Mat3,
    normal_m: Mat3,
    /// A mirroring transform (negative determinant).
    flip: bool,
}

fn add_mesh(
    src: &Source,
    mesh: &gltf::Mesh,
    world: Mat4,
    default_material: u32,
    want_uvs: bool,
    out: &mut Collected,
    skipped: &mut Skipped,
) -> Result<(), String> {
    let linear = Mat3::from_mat4(world);
    let place = Placement {
        world,
        linear,
        normal_m: normal_matrix(linear),
        flip: linear.determinant() < 0.0,
    };
    let mesh_label = match mesh.name() {
        Some(n) => format!("mesh {} ('{n}')", mesh.index()),
        None => format!("mesh {}", mesh.index()),
    };
    if mesh.primitives().len() == 0 {
        return Err(format!(
            "{mesh_label} has no primitives (glTF requires at least one)"
        ));
    }
    for prim in mesh.primitives() {
        let label = format!("{mesh_label} primitive {}", prim.index());
        add_primitive(src, &prim, default_material, &place, want_uvs, out, skipped)
            .map_err(|e| format!("{label}: {e}"))?;
    }
    Ok(())
}

/// One primitive's triangles (points and lines skipped, strips and fans
/// unrolled), with their shading records and texture coordinates.
fn add_primitive(
    src: &Source,
    prim: &gltf::Primitive,
    default_material: u32,
    place: &Placement,
    want_uvs: bool,
    out: &mut Collected,
    skipped: &mut Skipped,
) -> Result<(), String> {
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        // Points and lines have no area: nothing to render.
        skipped.points_lines += 1;
        return Ok(());
    }
    if prim.morph_targets().len() > 0 {
        skipped.morphs += 1;
    }
    let material = match prim.material().index() {
        Some(m) => m as u32,
        None => {
            out.uses_default_material = true;
            default_material
        }
    };
    let d = read_primitive(src, prim, want_uvs)?;
    let n_verts = d.positions.len();
    let n_refs = d.indices.as_ref().map_or(n_verts, Vec::len);
    if mode == Mode::Triangles && n_refs % 3 != 0 {
        let what = if d.indices.is_some() {
            "index"
        } else {
            "vertex"
        };
        return Err(format!(
            "{what} count {n_refs} is not a multiple of 3 (mode TRIANGLES)"
        ));
    }
    let n_tris = triangles_from_refs(mode, n_refs as u64) as usize;
    // Reserve only now that the data has been read: declared counts are
    // not trusted until their bytes have been found.
    out.triangles.reserve(n_tris);
    out.shading.reserve(n_tris);
    if want_uvs {
        out.uvs.reserve(n_tris);
    }
    let vertex = |k: usize| -> Result<usize, String> {
        let v = match &d.indices {
            Some(ix) => ix[k] as usize,
            None => k,
        };
        if v < n_verts {
            Ok(v)
        } else {
            Err(format!(
                "index {v} (at position {k}) is out of range: {n_verts} vertices"
            ))
        }
    };
    // Vertex order per glTF 2.0 spec section 3.7.2.1 (strips alternate
    // winding, fans pivot on vertex 0).
    let refs_of = |t: usize| match mode {
        Mode::Triangles => [3 * t, 3 * t + 1, 3 * t + 2],
        Mode::TriangleStrip if t.is_multiple_of(2) => [t, t + 1, t + 2],
        Mode::TriangleStrip => [t, t + 2, t + 1],
        _ => [t + 1, t + 2, 0],
    };
    let face = |t: usize| -> Result<[usize; 3], String> {
        let r = refs_of(t);
        Ok([vertex(r[0])?, vertex(r[1])?, vertex(r[2])?])
    };
    let mikk = generated_tangents(src, prim, &d, n_tris, &face)?;
    for t in 0..n_tris {
        let mikk_t = mikk
            .as_ref()
            .map(|m| [m[3 * t], m[3 * t + 1], m[3 * t + 2]]);
        push_triangle(t, face(t)?, &d, mikk_t, material, place, want_uvs, out)?;
    }
    Ok(())
}

/// Without TANGENT, a normal-mapped primitive gets MikkTSpace tangents
/// (glTF 2.0 sec. 3.7.2.1: what exporters bake against), per triangle
/// corner (`3 t + j`), in the normal texture's UV set; `None` otherwise.
fn generated_tangents(
    src: &Source,
    prim: &gltf::Primitive,
    d: &PrimData,
    n_tris: usize,
    face: &dyn Fn(usize) -> Result<[usize; 3], String>,
) -> Result<Option<Vec<[f32; 4]>>, String> {
    let uv = match (&d.tangents, normal_texcoord(src, prim.material().index())) {
        (None, Some(0)) => d.uvs.as_deref(),
        (None, Some(1)) => d.uvs1.as_deref(),
        _ => None,
    };
    let Some(uv) = uv else {
        return Ok(None);
    };
    let faces = (0..n_tris).map(face).collect::<Result<Vec<_>, String>>()?;
    Ok(Some(mikktspace_tangents(
        &d.positions,
        d.normals.as_deref(),
        uv,
        faces,
    )))
}

/// Triangle `t` of a primitive, vertices `v` of `d`: its world-space
/// record, shading record and texture coordinates. `mikk`: the generated
/// tangents at the file's three corners.
#[allow(clippy::too_many_arguments)]
fn push_triangle(
    t: usize,
    mut v: [usize; 3],
    d: &PrimData,
    mikk: Option<[[f32; 4]; 3]>,
    material: u32,
    place: &Placement,
    want_uvs: bool,
    out: &mut Collected,
) -> Result<(), String> {
    // Which corner of the file's triangle each of ours is.
    let mut corner = [0, 1, 2];
    if place.flip {
        // A mirroring transform reverses the winding; swapping two
        // vertices keeps counter-clockwise = outside.
        v.swap(1, 2);
        corner.swap(1, 2);
    }
    let p = v.map(|k| place.world.transform_point3(Vec3::from(d.positions[k])));
    if p.iter().any(|q| !q.is_finite()) {
        return Err(format!(
            "a transformed position overflows to a non-finite value (triangle {t})"
        ));
    }
    out.triangles.push(Triangle {
        p0: p[0].into(),
        material,
        p1: p[1].into(),
        light: crate::scene::NO_LIGHT,
        p2: p[2].into(),
        flags: 0,
    });
    let geo = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
    // The file's tangent (xyz) at each of our corners.
    let given: Option<[[f32; 4]; 3]> = match (&d.tangents, &mikk) {
        (Some(ts), _) => Some(v.map(|k| ts[k])),
        (None, Some(m)) => Some(corner.map(|j| m[j])),
        _ => None,
    };
    let mut sh = triangle_shading(
        v,
        p,
        geo,
        d.normals.as_deref(),
        place.normal_m,
        place.linear,
        given.as_ref(),
        d.uvs.as_deref(),
    );
    if geo != Vec3::ZERO && sh.t.iter().all(|t| t[3] == 0.0) {
        // Neither TANGENT nor a dP/du (no TEXCOORD_0, or a degenerate
        // mapping): dP/du of the triangle's barycentric parameterization,
        // its first edge in the file's vertex order, as Mitsuba 3 (3.9.1
        // measured: `dp_du` = p1 - p0 without texture coordinates) and
        // pbrt-v4 (default uv (0,0), (1,0), (1,1)) take it. The readers
        // project it onto the shading normal, so on a curved mesh the
        // lobe turns from face to face, as in both.
        let edge = if place.flip { p[2] - p[0] } else { p[1] - p[0] };
        sh.t = [edge.normalize_or_zero().extend(1.0).to_array(); 3];
    }
    out.shading.push(sh);
    if want_uvs {
        let uv = (d.uvs.as_deref(), d.uvs1.as_deref());
        out.uvs
            .push(triangle_uv(v, p, geo, given.as_ref(), uv, place.flip));
    }
    Ok(())
}

/// A triangle's shading record: its vertices' normals (through the normal
/// matrix; the geometric normal with w = 0 where NORMAL is missing or
/// degenerate) and tangents (`given` per corner, else dP/du from
/// TEXCOORD_0), `v` its vertex indices and `p` its world positions.
#[allow(clippy::too_many_arguments)]
fn triangle_shading(
    v: [usize; 3],
    p: [Vec3; 3],
    geo: Vec3,
    normals: Option<&[[f32; 3]]>,
    normal_m: Mat3,
    linear: Mat3,
    given: Option<&[[f32; 4]; 3]>,
    uvs: Option<&[[f32; 2]]>,
) -> TriangleShading {
    let mut sh = TriangleShading::default();
    let shading_normals = normals.and_then(|ns| {
        let n = v.map(|k| (normal_m * Vec3::from(ns[k])).normalize_or_zero());
        n.iter().all(|x| *x != Vec3::ZERO).then_some(n)
    });
    match shading_normals {
        Some(n) => sh.n = n.map(|x| x.extend(1.0).to_array()),
        // w = 0: no usable NORMAL; the geometric normal is stored for
        // convenience and readers use the geometric normal.
        None => sh.n = [geo.extend(0.0).to_array(); 3],
    }
    if let Some(ts) = given {
        for (slot, tg) in sh.t.iter_mut().zip(ts) {
            let t = linear * Vec3::from_slice(&tg[..3]);
            let t = t.normalize_or_zero();
            *slot = t.extend(if t != Vec3::ZERO { 1.0 } else { 0.0 }).to_array();
        }
    } else if let Some(uv) = uvs {
        let t = dpdu(p, v.map(|k| Vec2::from(uv[k])));
        let w = if t != Vec3::ZERO { 1.0 } else { 0.0 };
        sh.t = [t.extend(w).to_array(); 3];
    }
    sh
}

/// One TEXCOORD set of a primitive, if it has it.
type Uvs<'a> = Option<&'a [[f32; 2]]>;

/// A triangle's texture coordinates (TEXCOORD_0 and _1 per corner) and its
/// bitangent sign.
fn triangle_uv(
    v: [usize; 3],
    p: [Vec3; 3],
    geo: Vec3,
    given: Option<&[[f32; 4]; 3]>,
    (uvs, uvs1): (Uvs<'_>, Uvs<'_>),
    flip: bool,
) -> TriangleUv {
    let mut tuv = TriangleUv::default();
    for (j, &k) in v.iter().enumerate() {
        if let Some(uv) = uvs {
            tuv.uv[j][0] = uv[k][0];
            tuv.uv[j][1] = uv[k][1];
        }
        if let Some(uv) = uvs1 {
            tuv.uv[j][2] = uv[k][0];
            tuv.uv[j][3] = uv[k][1];
        }
    }
    // A mirroring transform turns cross(N, T) against the
    // bitangent it carries: the sign flips with it.
    let mirror = if flip { -1.0 } else { 1.0 };
    tuv.extra[0] = match (given, uvs) {
        // glTF: bitangent = cross(normal, tangent.xyz) * w.
        (Some(ts), _) if ts[0][3] < 0.0 => -mirror,
        (Some(_), _) => mirror,
        // Without TANGENT: the sign that makes the bitangent
        // point up the image (-dP/dv, glTF's v running down).
        (None, Some(uv)) => {
            let uvv = v.map(|k| Vec2::from(uv[k]));
            let (tu, tv) = (dpdu(p, uvv), dpdv(p, uvv));
            if geo.cross(tu).dot(-tv) < 0.0 {
                -1.0
            } else {
                1.0
            }
        }
        _ => 1.0,
    };
    tuv
}

/// The UV set (`texCoord`, as `KHR_texture_transform` may override it) of
/// material `material`'s normal texture, if it has one.
fn normal_texcoord(src: &Source, material: Option<usize>) -> Option<u64> {
    let info = &src.raw["materials"][material?]["normalTexture"];
    if info.is_null() {
        return None;
    }
    let ext = &info["extensions"]["KHR_texture_transform"]["texCoord"];
    Some(ext.as_u64().or(info["texCoord"].as_u64()).unwrap_or(0))
}

/// One primitive as `bevy_mikktspace` reads it: triangles of vertex
/// indices, and the tangent it writes per corner.
struct MikkMesh<'a> {
    positions: &'a [[f32; 3]],
    normals: Option<&'a [[f32; 3]]>,
    uvs: &'a [[f32; 2]],
    faces: Vec<[usize; 3]>,
    out: Vec<[f32; 4]>,
}

impl bevy_mikktspace::Geometry for MikkMesh<'_> {
    fn num_faces(&self) -> usize {
        self.faces.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.faces[face][vert]]
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        match self.normals {
            Some(n) => n[self.faces[face][vert]],
            // glTF: no NORMAL means flat shading, the face's own normal.
            None => {
                let p = self.faces[face].map(|k| Vec3::from(self.positions[k]));
                (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero().into()
            }
        }
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // MikkTSpace's bitangent follows +v; glTF's v runs down the image
        // and its normal maps' green runs up, so v is flipped, as Blender's
        // exporter (which computes tangents with v up) has it.
        let [u, v] = self.uvs[self.faces[face][vert]];
        [u, 1.0 - v]
    }
    fn set_tangent(
        &mut self,
        tangent_space: Option<bevy_mikktspace::TangentSpace>,
        face: usize,
        vert: usize,
    ) {
        self.out[3 * face + vert] = match tangent_space {
            Some(ts) => ts.tangent_encoded(),
            // No tangent (a degenerate face with no neighbour): w = 0 marks
            // it unknown and the frame is built from the normal.
            None => [0.0; 4],
        };
    }
}

/// MikkTSpace tangents (xyz, w = bitangent sign) of `faces`, three per
/// face in corner order, in the mesh's own space.
pub fn mikktspace_tangents(
    positions: &[[f32; 3]],
    normals: Option<&[[f32; 3]]>,
    uvs: &[[f32; 2]],
    faces: Vec<[usize; 3]>,
) -> Vec<[f32; 4]> {
    let mut m = MikkMesh {
        positions,
        normals,
        uvs,
        out: vec![[0.0; 4]; 3 * faces.len()],
        faces,
    };
    // The error type has no values: generation cannot fail.
    let _ = bevy_mikktspace::generate_tangents(&mut m);
    m.out
}

/// Triangles drawn from `refs` vertex references (glTF 2.0 spec 3.7.2.1);
/// TRIANGLES with a count not a multiple of 3 is refused before this.
fn triangles_from_refs(mode: Mode, refs: u64) -> u64 {
    match mode {
        Mode::Triangles => refs / 3,
        Mode::TriangleStrip | Mode::TriangleFan => refs.saturating_sub(2),
        _ => 0,
    }
}

/// The triangle count a mesh's accessors declare, before reading any data.
fn declared_triangles(root: &gltf::json::Root, mesh: &gltf::Mesh) -> u64 {
    mesh.primitives()
        .map(|p| {
            let acc = p.indices().or_else(|| p.get(&gltf::Semantic::Positions));
            let refs = acc
                .and_then(|a| root.accessors.get(a.index()))
                .map_or(0, |a| a.count.0);
            triangles_from_refs(p.mode(), refs)
        })
        .fold(0u64, u64::saturating_add)
}

/// dP/du of a triangle from its texture coordinates (pbrt-v4,
/// `Triangle::InteractionFromIntersection`): solve
/// [dp02 dp12] = [dpdu dpdv] [[du02 du12] [dv02 dv12]]. Zero when the UV
/// mapping is degenerate or not finite.
pub fn dpdu(p: [Vec3; 3], uv: [Vec2; 3]) -> Vec3 {
    let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
    let (dp02, dp12) = (p[0] - p[2], p[1] - p[2]);
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    if det.abs() < 1e-12 || !det.is_finite() {
        return Vec3::ZERO;
    }
    let d = (duv12.y * dp02 - duv02.y * dp12) / det;
    if d.is_finite() {
        d.normalize_or_zero()
    } else {
        Vec3::ZERO
    }
}

/// dP/dv of a triangle from its texture coordinates (the companion of
/// [`dpdu`]); zero when degenerate.
fn dpdv(p: [Vec3; 3], uv: [Vec2; 3]) -> Vec3 {
    let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
    let (dp02, dp12) = (p[0] - p[2], p[1] - p[2]);
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    if det.abs() < 1e-12 || !det.is_finite() {
        return Vec3::ZERO;
    }
    let d = (duv02.x * dp12 - duv12.x * dp02) / det;
    if d.is_finite() {
        d.normalize_or_zero()
    } else {
        Vec3::ZERO
    }
}

/// Light index of node `node` (KHR_lights_punctual), if any.
fn light_index(src: &Source, node: usize) -> Option<usize> {
    let n = src.doc.as_json().nodes.get(node)?;
    Some(
        n.extensions
            .as_ref()?
            .khr_lights_punctual
            .as_ref()?
            .light
            .value(),
    )
}

fn punctual(src: &Source, index: usize, world: Mat4) -> Result<PunctualLight, String> {
    let light = src
        .doc
        .as_json()
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .and_then(|l| l.lights.get(index))
        .ok_or_else(|| format!("light {index} does not exist"))?;
    let err = |e: String| format!("light {index}: {e}");
    let color = Vec3::from(light.color);
    if !(color.is_finite() && color.min_element() >= 0.0) {
        return Err(err(format!("color must be finite and >= 0, got {color}")));
    }
    if !(light.intensity.is_finite() && light.intensity >= 0.0) {
        return Err(err(format!(
            "intensity must be finite and >= 0, got {}",
            light.intensity
        )));
    }
    // No photometric conversion: color x intensity is radiometric as written.
    let intensity = color * light.intensity;
    let position = world.transform_point3(Vec3::ZERO);
    // Lights shine down their local -Z.
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if direction == Vec3::ZERO || !direction.is_finite() {
        return Err(err(
            "the node's transform collapses the light's direction".into()
        ));
    }
    Ok(match light.type_ {
        Checked::Valid(LightType::Point) => PunctualLight::Point {
            position,
            intensity,
        },
        Checked::Valid(LightType::Directional) => PunctualLight::Directional {
            direction,
            irradiance: intensity,
        },
        Checked::Valid(LightType::Spot) => {
            let (inner, outer) = light
                .spot
                .as_ref()
                .map_or((0.0, std::f32::consts::FRAC_PI_4), |s| {
                    (s.inner_cone_angle, s.outer_cone_angle)
                });
            // KHR_lights_punctual: 0 <= inner < outer <= pi/2.
            if !(inner >= 0.0 && inner < outer && outer <= std::f32::consts::FRAC_PI_2) {
                return Err(err(format!(
                    "spot cone angles need 0 <= innerConeAngle < outerConeAngle <= pi/2, got {inner} and {outer}"
                )));
            }
            PunctualLight::Spot {
                position,
                direction,
                intensity,
                inner_cone_angle: inner,
                outer_cone_angle: outer,
            }
        }
        Checked::Invalid => return Err(err("unknown light type".into())),
    })
}

/// A camera at `world` with the scale sheared out: -Z (the view direction)
/// is kept exactly, +Y is made orthogonal to it, and X completes a
/// right-handed frame, so a mirrored node cannot mirror the image.
fn camera(src: &Source, index: usize, world: Mat4) -> Result<Camera, String> {
    let json = src
        .doc
        .as_json()
        .cameras
        .get(index)
        .ok_or_else(|| format!("camera {index} does not exist"))?;
    let err = |e: String| format!("camera {index}: {e}");
    use gltf::json::camera::Type;
    let persp = match (&json.type_, &json.perspective) {
        (Checked::Valid(Type::Perspective), Some(p)) => p,
        (Checked::Valid(Type::Perspective), None) => {
            return Err(err(
                "type is perspective but there is no \"perspective\" object".into(),
            ));
        }
        _ => {
            return Err(err(
                "orthographic cameras are not supported (only perspective)".into(),
            ));
        }
    };
    if !(persp.yfov.is_finite() && persp.yfov > 0.0 && persp.yfov < std::f32::consts::PI) {
        return Err(err(format!("yfov must lie in (0, pi), got {}", persp.yfov)));
    }
    if let Some(a) = persp.aspect_ratio
        && !(a.is_finite() && a > 0.0)
    {
        return Err(err(format!("aspectRatio must be finite and > 0, got {a}")));
    }
    let z = world.z_axis.truncate().normalize_or_zero();
    let y = world.y_axis.truncate();
    let y = (y - y.dot(z) * z).normalize_or_zero();
    if z == Vec3::ZERO || y == Vec3::ZERO {
        return Err(err("the node's transform is degenerate (zero scale)".into()));
    }
    let x = y.cross(z);
    let to_world = Mat4::from_cols(
        x.extend(0.0),
        y.extend(0.0),
        z.extend(0.0),
        world.w_axis.truncate().extend(1.0),
    );
    Ok(Camera {
        name: json.name.clone(),
        node_name: None,
        to_world,
        yfov: persp.yfov,
        aspect_ratio: persp.aspect_ratio,
    })
}
