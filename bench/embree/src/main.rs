//! glint's CPU traversal against Embree 3 (Debian's libembree-dev 3.13) on
//! the same triangles and the same rays, one thread, in one run: the
//! traversal half of issue 24's comparison with Mitsuba 3, whose LLVM
//! variants trace with Embree.
//!
//! Run: `bash scripts/embree_bench.sh` (installs libembree-dev where it is
//! missing, then `cargo run --release` here). Meshes: the bunny and the
//! Cornell box (`assets/`), and `../shared/assets/nefertiti.glb` where it
//! exists. Rays: coherent primary rays from a pinhole camera (384 x 384)
//! and one cosine-distributed diffuse bounce off every primary hit, the
//! rays of `cpu/tests/bvh_throughput.rs` (`support/geometry.rs`). Queries:
//! closest hit and any hit. Each variant is timed on the same chunks of
//! rays interleaved with the others, best of three per chunk, so a change
//! of load on the shared machine falls on all alike. Embree is asked for
//! single rays (`rtcIntersect1` / `rtcOccluded1`), as Mitsuba's scalar and
//! LLVM variants call it per lane; its scene builds at its default
//! (medium) quality and at high quality (spatial splits).
//!
//! Agreement is printed, not assumed: the share of rays where both report
//! a hit (or both none) and, where both hit, the same distance within
//! 1e-4 relative.

#[path = "../../../cpu/tests/support/geometry.rs"]
mod geometry;
#[path = "../../../cpu/tests/support/timing.rs"]
mod timing;
use timing::interleaved;

use std::ffi::c_void;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glint_cpu::bvh::Kernel;
use glint_cpu::{Bvh4, Hit, Ray, Triangle};

mod ffi {
    use std::ffi::{c_char, c_void};

    pub const GEOMETRY_TYPE_TRIANGLE: u32 = 0;
    pub const BUFFER_TYPE_INDEX: u32 = 0;
    pub const BUFFER_TYPE_VERTEX: u32 = 1;
    pub const FORMAT_UINT3: u32 = 0x5003;
    pub const FORMAT_FLOAT3: u32 = 0x9003;
    pub const BUILD_QUALITY_MEDIUM: u32 = 1;
    pub const BUILD_QUALITY_HIGH: u32 = 2;
    pub const INVALID_GEOMETRY_ID: u32 = u32::MAX;

    /// `struct RTCRay` (rtcore_ray.h).
    #[repr(C, align(16))]
    #[derive(Clone, Copy, Default)]
    pub struct RtcRay {
        pub org: [f32; 3],
        pub tnear: f32,
        pub dir: [f32; 3],
        pub time: f32,
        pub tfar: f32,
        pub mask: u32,
        pub id: u32,
        pub flags: u32,
    }

    /// `struct RTCHit` with `RTC_MAX_INSTANCE_LEVEL_COUNT` 1.
    #[repr(C, align(16))]
    #[derive(Clone, Copy, Default)]
    pub struct RtcHit {
        pub ng: [f32; 3],
        pub u: f32,
        pub v: f32,
        pub prim_id: u32,
        pub geom_id: u32,
        pub inst_id: [u32; 1],
    }

    #[repr(C)]
    #[derive(Clone, Copy, Default)]
    pub struct RtcRayHit {
        pub ray: RtcRay,
        pub hit: RtcHit,
    }

    /// `struct RTCIntersectContext` (no instancing levels, no min width).
    #[repr(C)]
    pub struct RtcIntersectContext {
        pub flags: u32,
        pub filter: *const c_void,
        pub inst_id: [u32; 1],
    }

    unsafe extern "C" {
        pub fn rtcNewDevice(config: *const c_char) -> *mut c_void;
        pub fn rtcReleaseDevice(device: *mut c_void);
        pub fn rtcGetDeviceError(device: *mut c_void) -> u32;
        pub fn rtcNewScene(device: *mut c_void) -> *mut c_void;
        pub fn rtcReleaseScene(scene: *mut c_void);
        pub fn rtcSetSceneBuildQuality(scene: *mut c_void, quality: u32);
        pub fn rtcNewGeometry(device: *mut c_void, kind: u32) -> *mut c_void;
        pub fn rtcSetNewGeometryBuffer(
            geometry: *mut c_void,
            kind: u32,
            slot: u32,
            format: u32,
            byte_stride: usize,
            item_count: usize,
        ) -> *mut c_void;
        pub fn rtcCommitGeometry(geometry: *mut c_void);
        pub fn rtcAttachGeometry(scene: *mut c_void, geometry: *mut c_void) -> u32;
        pub fn rtcReleaseGeometry(geometry: *mut c_void);
        pub fn rtcCommitScene(scene: *mut c_void);
        pub fn rtcIntersect1(
            scene: *mut c_void,
            context: *mut RtcIntersectContext,
            rayhit: *mut RtcRayHit,
        );
        pub fn rtcOccluded1(
            scene: *mut c_void,
            context: *mut RtcIntersectContext,
            ray: *mut RtcRay,
        );
    }
}

/// One Embree device and scene holding one triangle mesh.
struct Embree {
    device: *mut c_void,
    scene: *mut c_void,
}

impl Embree {
    fn new(tris: &[Triangle], quality: u32) -> Embree {
        // SAFETY: the Embree 3 API as documented; buffers are filled within
        // the sizes Embree allocated for them.
        unsafe {
            let device = ffi::rtcNewDevice(c"threads=1".as_ptr());
            assert!(!device.is_null(), "rtcNewDevice failed");
            let scene = ffi::rtcNewScene(device);
            ffi::rtcSetSceneBuildQuality(scene, quality);
            let geom = ffi::rtcNewGeometry(device, ffi::GEOMETRY_TYPE_TRIANGLE);
            let n = tris.len();
            let v = ffi::rtcSetNewGeometryBuffer(
                geom,
                ffi::BUFFER_TYPE_VERTEX,
                0,
                ffi::FORMAT_FLOAT3,
                12,
                3 * n,
            ) as *mut [f32; 3];
            let idx = ffi::rtcSetNewGeometryBuffer(
                geom,
                ffi::BUFFER_TYPE_INDEX,
                0,
                ffi::FORMAT_UINT3,
                12,
                n,
            ) as *mut [u32; 3];
            for (i, t) in tris.iter().enumerate() {
                *v.add(3 * i) = t.p0;
                *v.add(3 * i + 1) = t.p1;
                *v.add(3 * i + 2) = t.p2;
                let k = 3 * i as u32;
                *idx.add(i) = [k, k + 1, k + 2];
            }
            ffi::rtcCommitGeometry(geom);
            ffi::rtcAttachGeometry(scene, geom);
            ffi::rtcReleaseGeometry(geom);
            ffi::rtcCommitScene(scene);
            assert_eq!(ffi::rtcGetDeviceError(device), 0, "Embree error");
            Embree { device, scene }
        }
    }

    fn context() -> ffi::RtcIntersectContext {
        ffi::RtcIntersectContext {
            flags: 0,
            filter: std::ptr::null(),
            inst_id: [ffi::INVALID_GEOMETRY_ID],
        }
    }

    fn ray(r: &Ray) -> ffi::RtcRay {
        ffi::RtcRay {
            org: r.o.into(),
            tnear: 0.0,
            dir: r.d.into(),
            tfar: r.tmax,
            mask: u32::MAX,
            ..Default::default()
        }
    }

    /// Closest hit distance and primitive.
    fn intersect(&self, r: &Ray) -> Option<(f32, u32)> {
        let mut rh = ffi::RtcRayHit {
            ray: Self::ray(r),
            hit: ffi::RtcHit {
                geom_id: ffi::INVALID_GEOMETRY_ID,
                ..Default::default()
            },
        };
        let mut ctx = Self::context();
        // SAFETY: a committed scene, a valid context and ray.
        unsafe { ffi::rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        (rh.hit.geom_id != ffi::INVALID_GEOMETRY_ID).then_some((rh.ray.tfar, rh.hit.prim_id))
    }

    fn occluded(&self, r: &Ray) -> bool {
        let mut ray = Self::ray(r);
        let mut ctx = Self::context();
        // SAFETY: as above.
        unsafe { ffi::rtcOccluded1(self.scene, &mut ctx, &mut ray) };
        ray.tfar == f32::NEG_INFINITY
    }
}

impl Drop for Embree {
    fn drop(&mut self) {
        // SAFETY: released once, scene before device.
        unsafe {
            ffi::rtcReleaseScene(self.scene);
            ffi::rtcReleaseDevice(self.device);
        }
    }
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn mesh(path: &Path) -> Vec<Triangle> {
    geometry::file_triangles(path)
}

/// Agreement of Embree's closest hits with glint's: (same hit or miss,
/// same distance within 1e-4 relative where both hit), as shares.
fn agreement(glint: &[Option<Hit>], embree: &[Option<(f32, u32)>]) -> (f64, f64) {
    let n = glint.len() as f64;
    let (mut status, mut dist, mut both) = (0usize, 0usize, 0usize);
    for (g, e) in glint.iter().zip(embree) {
        if g.is_some() == e.is_some() {
            status += 1;
        }
        if let (Some(g), Some((t, _))) = (g, e) {
            both += 1;
            if (g.t - t).abs() <= 1e-4 * g.t.abs().max(1e-6) {
                dist += 1;
            }
        }
    }
    (status as f64 / n, dist as f64 / both.max(1) as f64)
}

fn measure(name: &str, input: &[Triangle]) {
    let t0 = Instant::now();
    // The render's trees (`Scene::build_bvh`): the GPU's and the CPU's
    // 8-wide one, built side by side.
    let (wide, order) = Bvh4::build(input);
    let tris: Vec<Triangle> = order.iter().map(|&i| input[i as usize]).collect();
    let glint_build = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let medium = Embree::new(&tris, ffi::BUILD_QUALITY_MEDIUM);
    let medium_build = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let high = Embree::new(&tris, ffi::BUILD_QUALITY_HIGH);
    let high_build = t0.elapsed().as_secs_f64();
    println!(
        "\n### {name}: {} triangles\n\nBuild: glint {:.1} ms (both trees: binned SAH, one for the GPU's 4-wide nodes, one for the CPU's 8-wide nodes and four-triangle blocks, two threads), \
         Embree medium {:.1} ms, high {:.1} ms.\n",
        tris.len(),
        glint_build * 1e3,
        medium_build * 1e3,
        high_build * 1e3
    );
    let (lo, hi) = geometry::bounds_of(&tris);
    let primary = geometry::primary_rays(lo, hi, 384, 384);
    let hits: Vec<Option<Hit>> = primary.iter().map(|r| wide.intersect(&tris, r)).collect();
    let diffuse =
        geometry::diffuse_rays(&tris, &primary, &hits, &mut geometry::Pcg32::from_state(9));
    println!(
        "| rays | query | glint Mrays/s | Embree medium | Embree high | glint / Embree medium | \
         glint / Embree high | agreement (hit, distance) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---|");
    let mrays = |n: usize, s: f64| n as f64 / s / 1e6;
    let kernel = Kernel::best();
    for (set, rays) in [("primary", &primary), ("diffuse", &diffuse)] {
        let g: Vec<Option<Hit>> = rays.iter().map(|r| wide.intersect(&tris, r)).collect();
        let e: Vec<Option<(f32, u32)>> = rays.iter().map(|r| medium.intersect(r)).collect();
        let (same_status, same_dist) = agreement(&g, &e);
        for any in [false, true] {
            let query = if any { "any hit" } else { "closest" };
            let glint = |c: &[Ray]| -> usize {
                if any {
                    c.iter()
                        .filter(|r| wide.occluded_with(kernel, &tris, r))
                        .count()
                } else {
                    c.iter()
                        .filter_map(|r| wide.intersect_with(kernel, &tris, r))
                        .count()
                }
            };
            let em = |c: &[Ray]| -> usize {
                if any {
                    c.iter().filter(|r| medium.occluded(r)).count()
                } else {
                    c.iter().filter_map(|r| medium.intersect(r)).count()
                }
            };
            let eh = |c: &[Ray]| -> usize {
                if any {
                    c.iter().filter(|r| high.occluded(r)).count()
                } else {
                    c.iter().filter_map(|r| high.intersect(r)).count()
                }
            };
            let s = interleaved(rays, 4096, &[&glint, &em, &eh]);
            println!(
                "| {set} ({}) | {query} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4}, {:.4} |",
                rays.len(),
                mrays(rays.len(), s[0]),
                mrays(rays.len(), s[1]),
                mrays(rays.len(), s[2]),
                s[1] / s[0],
                s[2] / s[0],
                same_status,
                same_dist
            );
        }
    }
}

fn main() {
    println!(
        "glint {kernel:?} traversal (the 8-wide tree where the kernel is Avx2x8) against Embree 3.13 (`rtcIntersect1`/`rtcOccluded1`), one thread.",
        kernel = Kernel::best()
    );
    let root = repo();
    measure("bunny", &mesh(&root.join("assets/bunny.glb")));
    measure("cornell", &mesh(&root.join("assets/cornell.gltf")));
    let nef = root.join("../shared/assets/nefertiti.glb");
    if nef.is_file() {
        measure("nefertiti", &mesh(&nef));
    } else {
        println!("\n../shared/assets/nefertiti.glb not found: skipped");
    }
}
