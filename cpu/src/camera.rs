//! Primary rays: a glTF perspective camera with a one-pixel box filter.

use glam::{Vec2, Vec3};

use crate::bvh::Ray;
use crate::lanes::{Lane, V2, V3};
use crate::scene::{Camera, Scene};

/// A perspective camera prepared for one image size: the world-space origin
/// and the three axes, `right` and `up` pre-scaled by the half-extent of the
/// image plane at distance 1, so a ray direction is a single affine mix
/// (mirrored by `camera_ray` in `shaders/integrator/camera.glsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    pub origin: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    pub width: u32,
    pub height: u32,
}

impl PinholeCamera {
    /// glTF: the camera looks down its local -Z with +Y up; `yfov` is the
    /// vertical field of view; the aspect comes from the image size (the
    /// contract), not from the file's `aspectRatio`.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let m = camera.to_world;
        let origin = m.transform_point3(Vec3::ZERO);
        // Normalise the axes so a stray scale in the node transform cannot
        // change the field of view.
        let x = m.transform_vector3(Vec3::X).normalize_or(Vec3::X);
        let y = m.transform_vector3(Vec3::Y).normalize_or(Vec3::Y);
        let z = m.transform_vector3(Vec3::Z).normalize_or(Vec3::Z);
        let tan_half = (0.5 * camera.yfov).tan();
        let aspect = width as f32 / height as f32;
        Self {
            origin,
            right: x * (tan_half * aspect),
            up: y * tan_half,
            forward: -z,
            width,
            height,
        }
    }

    /// The ray through pixel (x, y) (top row first) at offset `u` in [0,1)^2
    /// within the pixel: a box filter one pixel wide.
    pub fn ray(&self, x: u32, y: u32, u: Vec2) -> Ray {
        Ray {
            o: self.origin,
            d: self.directions::<f32>(x, y, u.into()).into(),
            tmax: f32::MAX,
        }
    }

    /// The directions of [`Self::ray`] at the offsets `u`, lane by lane
    /// (the wave's camera rays; its one-lane instantiation is the scalar
    /// form).
    #[inline(always)]
    pub fn directions<L: Lane>(&self, x: u32, y: u32, u: V2<L>) -> V3<L> {
        let two = L::splat(2.0);
        let sx = two * (L::splat(x as f32) + u.x) / L::splat(self.width as f32) - L::one();
        let sy = L::one() - two * (L::splat(y as f32) + u.y) / L::splat(self.height as f32);
        let along = |axis: Vec3, s: L| V3::splat(axis).scale(s);
        (V3::splat(self.forward) + along(self.right, sx) + along(self.up, sy)).normalize()
    }
}

/// The camera a render uses: `Scene::cameras[index]`, or the documented
/// default viewpoint when the scene has no camera.
pub fn scene_camera(scene: &Scene, index: usize) -> Camera {
    match scene.cameras.get(index) {
        Some(c) => c.clone(),
        None => crate::loader::default_camera(scene),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;

    #[test]
    fn centre_ray_looks_down_minus_z_and_corners_span_the_fov() {
        let cam = Camera {
            name: None,
            node_name: None,
            to_world: Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)),
            yfov: std::f32::consts::FRAC_PI_2,
            aspect_ratio: None,
        };
        let pc = PinholeCamera::new(&cam, 200, 100);
        let r = pc.ray(100, 50, Vec2::ZERO);
        assert!((r.o - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
        assert!((r.d - Vec3::NEG_Z).length() < 1e-6);
        // Top-left corner: yfov 90 degrees -> tan = 1 vertically, 2 horizontally.
        let c = pc.ray(0, 0, Vec2::ZERO).d;
        let expect = Vec3::new(-2.0, 1.0, -1.0).normalize();
        assert!((c - expect).length() < 1e-6, "{c}");
    }
}
