//! Cameras: perspective (standard, reverse-Z, infinite far) and orthographic.
//!
//! The visibility buffer stores **view depth** (distance along the viewing axis, positive in front
//! of the camera), not NDC depth, so reverse-Z and an infinite far plane change the projection
//! matrix but not which surface is visible.

use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_at_mat4;
use glam::{Mat4, Vec3};

/// How a camera projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// A perspective projection.
    Perspective {
        /// Vertical field of view in degrees.
        fov_y_deg: f32,
        /// Near plane distance (> 0).
        near: f32,
        /// Far plane distance; `None` for an infinite far plane.
        far: Option<f32>,
        /// Depth 1 at the near plane and 0 at the far plane.
        reverse_z: bool,
    },
    /// An orthographic projection.
    Orthographic {
        /// Height of the view volume in scene units.
        height: f32,
        /// Near plane distance (may be negative).
        near: f32,
        /// Far plane distance.
        far: f32,
    },
}

/// A thin lens: the disc rays pass through and the distance that is sharp. A radius of 0 is a
/// pinhole (the default): everything is sharp and no depth-of-field pass runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lens {
    /// Radius of the aperture, in scene units (0: pinhole).
    pub radius: f32,
    /// View depth of the plane in focus, in scene units (> 0 when `radius` > 0).
    pub focus: f32,
}

impl Lens {
    /// Whether the lens blurs anything (a radius above 0).
    pub fn blurs(&self) -> bool {
        self.radius > 0.0
    }
}

/// A camera: where it is, where it looks, how it projects, and its lens.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Projection.
    pub projection: Projection,
    /// The lens (a pinhole by default; depth of field for a perspective camera otherwise).
    pub lens: Lens,
}

impl Camera {
    /// This camera turned `degrees` about its target, around its up axis (the eye moves, the
    /// target stays).
    pub fn orbited(&self, degrees: f32) -> Camera {
        let turn = glam::Quat::from_axis_angle(self.up.normalize(), degrees.to_radians());
        Camera { eye: self.target + turn * (self.eye - self.target), ..self.clone() }
    }

    /// A perspective camera with an infinite far plane.
    pub fn perspective(eye: Vec3, target: Vec3, fov_y_deg: f32, near: f32) -> Camera {
        Camera {
            eye,
            target,
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y_deg, near, far: None, reverse_z: false },
            lens: Lens::default(),
        }
    }

    /// The view matrix (world to view space, right-handed, looking down -z).
    pub fn view(&self) -> Mat4 {
        let forward = self.target - self.eye;
        // Pick another up vector when looking straight along `up`.
        let up = if forward.cross(self.up).length_squared() < 1e-12 * forward.length_squared() {
            if self.up.abs().dot(Vec3::Z) > 0.9 { Vec3::X } else { Vec3::Z }
        } else {
            self.up
        };
        look_at_mat4(self.eye, self.target, up)
    }

    /// The projection matrix for a width/height ratio (wgpu clip conventions, depth in [0, 1]).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective { fov_y_deg, near, far, reverse_z } => {
                let fov = fov_y_deg.to_radians();
                match (far, reverse_z) {
                    (None, false) => directx::perspective_infinite(fov, aspect, near),
                    (None, true) => directx::perspective_infinite_reverse(fov, aspect, near),
                    (Some(far), false) => directx::perspective(fov, aspect, near, far),
                    (Some(far), true) => directx::perspective(fov, aspect, far, near),
                }
            }
            Projection::Orthographic { height, near, far } => {
                let h = height * 0.5;
                let w = h * aspect;
                directx::orthographic(-w, w, -h, h, near, far)
            }
        }
    }

    /// Near and far view depths (`far` is `f32::MAX` for an infinite far plane).
    pub fn depth_range(&self) -> (f32, f32) {
        match self.projection {
            Projection::Perspective { near, far, .. } => (near, far.unwrap_or(f32::MAX)),
            Projection::Orthographic { near, far, .. } => (near, far),
        }
    }

    /// How many pixels of an image `height` pixels tall a world-space `length` spans, facing
    /// the camera at view distance `distance`: `length * height / (2 distance tan(fov_y / 2))`
    /// for a perspective camera, `length * height / view height` at any distance for an
    /// orthographic one.
    pub fn pixels_of(&self, length: f32, distance: f32, height: u32) -> f32 {
        match self.projection {
            Projection::Perspective { fov_y_deg, .. } => {
                length * height as f32 / (2.0 * distance * (fov_y_deg.to_radians() * 0.5).tan())
            }
            Projection::Orthographic { height: view, .. } => length * height as f32 / view,
        }
    }

    /// Whether the projection is orthographic.
    pub fn is_orthographic(&self) -> bool {
        matches!(self.projection, Projection::Orthographic { .. })
    }

    /// Checks that the camera can produce an image: finite, distinct eye and target, an `up` that
    /// is neither zero nor along the view, a field of view of at least [`MIN_FOV_DEG`].
    pub fn validate(&self) -> crate::Result<()> {
        let bad = |m: &str| Err(crate::Error::setting("camera", m.to_string()));
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return bad("eye, target and up must be finite");
        }
        let forward = self.target - self.eye;
        if forward.length_squared() == 0.0 {
            return bad("eye and target coincide");
        }
        if self.up.length_squared() == 0.0 {
            return bad("up is zero");
        }
        if forward.normalize().cross(self.up.normalize()).length_squared() < 1e-12 {
            return bad("up is parallel to the view direction");
        }
        match self.projection {
            Projection::Perspective { fov_y_deg, near, far, .. } => {
                if !(MIN_FOV_DEG..180.0).contains(&fov_y_deg) {
                    return bad("field of view must be in [0.001, 180) degrees");
                }
                if !(near > 0.0 && near.is_finite()) {
                    return bad("near must be positive and finite");
                }
                if let Some(far) = far
                    && !(far > near && far.is_finite())
                {
                    return bad("far must be finite and beyond near");
                }
            }
            Projection::Orthographic { height, near, far } => {
                if !(height > 0.0 && height.is_finite()) {
                    return bad("orthographic height must be positive");
                }
                if !(far > near && near.is_finite() && far.is_finite()) {
                    return bad("far must be finite and beyond near");
                }
            }
        }
        let lens = self.lens;
        if !(lens.radius.is_finite() && lens.radius >= 0.0) {
            return bad("the lens radius (aperture) must be finite and >= 0");
        }
        if lens.blurs() {
            if self.is_orthographic() {
                return bad("a lens with an aperture needs a perspective camera");
            }
            if !(lens.focus.is_finite() && lens.focus > 0.0) {
                return bad("the focus distance must be finite and > 0 when the aperture is open");
            }
        }
        Ok(())
    }
}

/// The narrowest vertical field of view accepted, in degrees (narrower ones make the projection's
/// scale overflow the rasterizer's fixed point for ordinary scene sizes).
pub const MIN_FOV_DEG: f32 = 0.001;
