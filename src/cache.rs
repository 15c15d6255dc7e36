//! The user's cache folder, shared by the cached converge references and
//! the Vulkan pipeline cache: `$GLINT_CACHE_DIR`, else
//! `$XDG_CACHE_HOME/glint`, else `~/.cache/glint`.

use std::path::{Path, PathBuf};

use glint_cpu::prepare::PrepareOptions;
use glint_cpu::{RenderOptions, Scene};

pub fn cache_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("GLINT_CACHE_DIR").filter(|d| !d.is_empty()) {
        return Some(PathBuf::from(d));
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME").filter(|d| !d.is_empty()) {
        return Some(PathBuf::from(d).join("glint"));
    }
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache").join("glint"))
}

/// The Vulkan pipeline cache file.
pub fn pipeline_cache_path() -> Option<PathBuf> {
    cache_dir().map(|d| d.join("pipelines.bin"))
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// 64-bit FNV-1a of `bytes`: a stable content hash for the files in the
/// cache (std's hasher may change between Rust releases, which would
/// silently orphan every cached file).
pub fn fnv64(bytes: &[u8]) -> u64 {
    fnv1a(FNV_OFFSET, bytes)
}

fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(FNV_PRIME);
    }
    h
}

/// FNV-1a over several fields, each followed by a separator so that
/// ("ab", "c") and ("a", "bc") differ: the cache and shard keys.
pub struct Fnv(pub u64);

impl Fnv {
    pub fn new() -> Self {
        Fnv(FNV_OFFSET)
    }

    pub fn add(&mut self, bytes: &[u8]) {
        self.0 = fnv1a(self.0, bytes).rotate_left(7) ^ 0xff;
    }
}

impl Default for Fnv {
    fn default() -> Self {
        Self::new()
    }
}

/// What a [`render_key`] covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyScope {
    /// What defines the expected image apart from its samples: the scene's
    /// files ([`SourceKey`]), size, camera, depth and methods. Shards of
    /// one image share it; `merge` checks seeds, samplers and sample ranges
    /// on their own, so it can say which one differs. It does not depend on
    /// glint's own code, so a reference another glint version made keeps
    /// its key: `glint test` then compares the two images, which is what a
    /// regression test of an upgrade asks.
    Image,
    /// One render exactly: the image's key plus the loaded scene as this
    /// glint holds it, the sample count, seed, sampler, first sample and
    /// glint's version (the converge reference cache).
    Render,
}

/// The scene's files and the options that change what they load into
/// (`--multiscatter`, `--background`, the environment map's scale and
/// turn): the bytes of every file the preparation read (the scene, its
/// external buffers and images, the environment map), in the order given,
/// and none of their paths. `prepare` lists its files in an order that
/// does not depend on how the scene was named ([`Prepared::inputs`]), so a
/// scene named by a relative or an absolute path, from any working folder
/// or under another name, keeps its key, and so does a suite moved to
/// another folder.
///
/// [`Prepared::inputs`]: glint_cpu::prepare::Prepared::inputs
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SourceKey(u64);

/// Versions of the key's form: a change of what [`SourceKey`] or
/// [`render_key`] hash takes a new one.
const KEY_FORM: &[u8] = b"glint image key 2";

/// 16 hex digits, as the EXR's `glint.files` records it.
impl std::fmt::Display for SourceKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:016x}", self.0)
    }
}

impl SourceKey {
    pub fn of(inputs: &[PathBuf], o: &PrepareOptions) -> std::io::Result<SourceKey> {
        let mut h = Fnv::new();
        h.add(KEY_FORM);
        for f in inputs {
            h.add(&fnv_file(f)?.to_le_bytes());
        }
        let bits = |v: glam::Vec3| v.to_array().map(f32::to_bits);
        h.add(
            format!(
                "multiscatter {} background {:?} envmap {:?}",
                o.multiscatter,
                o.background.map(bits),
                o.envmap
                    .as_ref()
                    .map(|e| (e.scale.to_bits(), e.rotate_degrees.to_bits()))
            )
            .as_bytes(),
        );
        Ok(SourceKey(h.0))
    }
}

/// [`fnv64`] of a file's bytes, read in blocks; only a regular file is
/// opened, without waiting (`safe_fs::open_regular`: a file swapped for a
/// FIFO since the scene was read cannot hang the render).
fn fnv_file(path: &Path) -> std::io::Result<u64> {
    use std::io::Read;
    let mut f = glint_cpu::safe_fs::open_regular(path)
        .map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))?;
    let mut buf = vec![0u8; 1 << 16];
    let mut h = FNV_OFFSET;
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            return Ok(h);
        }
        h = fnv1a(h, &buf[..n]);
    }
}

/// The one content key of a render (16 hex digits): the scene's files
/// (`source`), the options in `scope`, and for [`KeyScope::Render`] the
/// loaded scene too.
pub fn render_key(
    source: SourceKey,
    scene: &Scene,
    opts: &RenderOptions,
    scope: KeyScope,
) -> String {
    let mut h = Fnv::new();
    h.add(&source.0.to_le_bytes());
    if scope == KeyScope::Render {
        h.add(env!("CARGO_PKG_VERSION").as_bytes());
        hash_scene(&mut h, scene);
    }
    h.add(
        format!(
            "{}x{} depth {} camera {} {:?} {:?} {:?}",
            opts.width,
            opts.height,
            opts.max_depth,
            opts.camera,
            opts.nee,
            opts.mis,
            opts.light_sampling
        )
        .as_bytes(),
    );
    if scope == KeyScope::Render {
        h.add(
            format!(
                "spp {} seed {} {:?} from {}",
                opts.spp, opts.seed, opts.sampler, opts.sample_start
            )
            .as_bytes(),
        );
    }
    format!("{:016x}", h.0)
}

/// Add what the loaded scene holds to `h`: geometry, shading data,
/// materials, lights, cameras, background, textures and environment map.
fn hash_scene(h: &mut Fnv, scene: &Scene) {
    h.add(bytemuck::cast_slice(&scene.triangles));
    h.add(bytemuck::cast_slice(&scene.shading));
    h.add(
        format!(
            "{:?}|{:?}|{:?}|{:?}",
            scene.materials, scene.lights, scene.cameras, scene.background
        )
        .as_bytes(),
    );
    let t = &scene.textures;
    h.add(bytemuck::cast_slice(&t.texels));
    h.add(format!("{:?}|{:?}|{:?}", t.table, t.materials, t.uvs).as_bytes());
    if let Some(e) = &scene.envmap {
        h.add(bytemuck::cast_slice(&e.texels));
        h.add(format!("{}x{} {}", e.width, e.height, e.rotation).as_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_cpu::prepare::EnvmapSource;

    #[test]
    fn source_key_is_the_files_bytes_in_order_and_the_scene_options() {
        let t = tempfile::tempdir().unwrap();
        let (a, b) = (t.path().join("a.bin"), t.path().join("b.png"));
        std::fs::write(&a, [1u8, 2, 3]).unwrap();
        std::fs::write(&b, [4u8; 100_000]).unwrap();
        let o = PrepareOptions::default();
        let k = SourceKey::of(&[a.clone(), b.clone()], &o).unwrap();
        let c = t.path().join("sub").join("c.bin");
        std::fs::create_dir(t.path().join("sub")).unwrap();
        std::fs::copy(&a, &c).unwrap();
        assert_eq!(SourceKey::of(&[c, b.clone()], &o).unwrap(), k, "paths");
        assert_ne!(SourceKey::of(&[b.clone(), a.clone()], &o).unwrap(), k);
        let env = |scale| PrepareOptions {
            envmap: Some(EnvmapSource {
                path: b.clone(),
                scale,
                rotate_degrees: 0.0,
            }),
            ..PrepareOptions::default()
        };
        let keys = [
            SourceKey::of(std::slice::from_ref(&a), &o).unwrap(),
            SourceKey::of(&[a.clone(), b.clone()], &env(1.0)).unwrap(),
            SourceKey::of(&[a.clone(), b.clone()], &env(2.0)).unwrap(),
        ];
        assert!(keys.iter().all(|x| *x != k) && keys[1] != keys[2]);
        // A byte past the first read block.
        let mut bytes = vec![4u8; 100_000];
        bytes[99_999] = 5;
        std::fs::write(&b, bytes).unwrap();
        assert_ne!(SourceKey::of(&[a.clone(), b.clone()], &o).unwrap(), k);
        std::fs::remove_file(&b).unwrap();
        assert!(SourceKey::of(&[a.clone(), b.clone()], &o).is_err());
        // A FIFO in a file's place: an error at once, not a wait.
        let c = std::ffi::CString::new(b.to_str().unwrap()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = SourceKey::of(&[a, b], &o).unwrap_err().to_string();
        assert!(e.contains("FIFO"), "{e}");
    }
}
