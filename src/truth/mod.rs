//! Ground truth by ray tracing on the CPU, for the accuracy figures: what each screen-space
//! approximation would be if it could see the whole scene.
//!
//! A [`Tracer`] holds the scene's triangles in a compressed wide BVH (the `obvhs` crate). Primary
//! rays go through pixel centres exactly as the rasterizer samples them, and the surface they hit
//! is resolved by the CPU resolve ([`crate::cpu::resolve::resolve_pixel`]), so a truth image and
//! a GPU frame describe the same points with the same normals. Pixels are traced in parallel
//! (rayon); each pixel draws its samples from its own seeded stream, so a run is reproducible
//! whatever the thread count.

pub mod metrics;

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec3A, Vec4Swizzles};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::cpu::frame::{mat_mul, view_position};
use crate::cpu::reflections::{lobe_direction, reflectance};
use crate::environment::Environment;
use crate::frame::CameraMatrices;
use crate::frame::FrameUniform;
use crate::gbuffer::{GSample, vis_pack};
use crate::scene::{AlphaMode, Camera, GpuLight, Scene};
use crate::settings::AoSettings;
use crate::{Error, Result};

/// A scene's triangles in a BVH, ready for rays.
pub struct Tracer {
    bvh: CwBvh,
    triangles: Vec<Triangle>,
    /// Per triangle: back faces are culled for primary rays (single-sided material).
    single_sided: Vec<bool>,
    /// A length on the scale of the scene (its bounds' diagonal), for ray offsets.
    scale: f32,
    /// Per triangle: how its material's opacity is used.
    alpha: Vec<AlphaMode>,
    /// The scene, kept when some triangle's opacity must be read at its hits (a masked or
    /// blended material).
    translucent: Option<Box<Scene>>,
}

/// Instants of the shutter at which [`Tracer::full_in_motion`] stands moving geometry.
pub const SHUTTER_INSTANTS: usize = 32;

/// What moved while the shutter was open, for [`Tracer::full_in_motion`].
#[derive(Clone, Copy, Debug)]
pub struct Shutter<'a> {
    /// The camera of the frame before (the shot's own if the camera stood still).
    pub before: &'a Camera,
    /// The share of the time between the frames the shutter stays open up to the shot's
    /// instant, in [0, 1].
    pub open: f32,
    /// Each vertex's position in the frame before (`None`: the geometry stood still).
    pub positions_before: Option<&'a [Vec3]>,
}

impl Shutter<'_> {
    /// The camera alone moved.
    pub fn camera(before: &Camera, open: f32) -> Shutter<'_> {
        Shutter { before, open, positions_before: None }
    }

    /// Checks the shutter against `scene`; with moving geometry, the instants of the shutter:
    /// (the share of the way from the frame before, a tracer and the scene as it stood then).
    fn instants(&self, scene: &Scene) -> Result<Vec<(f32, Tracer, Scene)>> {
        self.before.validate()?;
        if !(0.0..=1.0).contains(&self.open) {
            return Err(Error::setting("shutter", format!("{} (must be in [0, 1])", self.open)));
        }
        let Some(before) = self.positions_before else { return Ok(Vec::new()) };
        if before.len() != scene.positions.len() {
            return Err(Error::InvalidScene(format!(
                "{} positions before the shutter for {} vertices",
                before.len(),
                scene.positions.len()
            )));
        }
        if let Some(i) = before.iter().position(|p| !p.is_finite()) {
            return Err(Error::InvalidScene(format!(
                "position {i} before the shutter is not finite"
            )));
        }
        (0..SHUTTER_INSTANTS)
            .map(|k| {
                let t = 1.0 - self.open * (k as f32 + 0.5) / SHUTTER_INSTANTS as f32;
                let positions = before.iter().zip(&scene.positions).map(|(a, b)| a.lerp(*b, t));
                let at = Scene { positions: positions.collect(), ..scene.clone() };
                Ok((t, Tracer::new(&at)?, at))
            })
            .collect()
    }
}

/// SplitMix64's finaliser: a well-mixed 64-bit hash.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Barycentrics of `point` in the plane of triangle (a, b, c), clamped (the centroid for a
/// degenerate triangle).
fn plane_barycentrics(a: Vec3, b: Vec3, c: Vec3, point: Vec3) -> Vec3 {
    let geo = (b - a).cross(c - a);
    let area = geo.length_squared();
    if area > 0.0 {
        let u = (c - b).cross(point - b).dot(geo) / area;
        let v = (a - c).cross(point - c).dot(geo) / area;
        Vec3::new(u, v, 1.0 - u - v).clamp(Vec3::ZERO, Vec3::ONE)
    } else {
        Vec3::splat(1.0 / 3.0)
    }
}

/// A ground-truth image: per pixel the estimate, its standard error (the estimate's own noise,
/// the floor under any comparison), and whether a surface is visible there.
#[derive(Clone, Debug)]
pub struct TruthImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The estimate (rgb; scalar effects repeat one value).
    pub value: Vec<Vec3>,
    /// Standard error of the estimate (sample standard deviation over sqrt(spp)).
    pub stderr: Vec<Vec3>,
    /// The primary ray hit a surface.
    pub visible: Vec<bool>,
}

impl TruthImage {
    /// The mean standard error over visible pixels (first channel).
    pub fn mean_stderr(&self) -> f32 {
        let (sum, n) = self
            .stderr
            .iter()
            .zip(&self.visible)
            .filter(|(_, v)| **v)
            .fold((0.0f64, 0usize), |(s, n), (e, _)| (s + f64::from(e.x), n + 1));
        if n == 0 { 0.0 } else { (sum / n as f64) as f32 }
    }
}

/// What a truth image is traced for: the camera, the image size, the rays per pixel and the
/// seed of the per-pixel sample streams.
#[derive(Clone, Debug)]
pub struct Shot<'a> {
    /// The camera (its pixel centres are the primary rays).
    pub camera: &'a Camera,
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the sample streams (the same seed gives the same image).
    pub seed: u64,
}

impl Shot<'_> {
    /// The frame uniform of the shot (no history), after checking its size, samples and camera.
    pub fn frame(&self) -> Result<FrameUniform> {
        let (width, height) = self.size;
        if width == 0
            || height == 0
            || width > crate::frame::MAX_IMAGE_SIDE
            || height > crate::frame::MAX_IMAGE_SIDE
        {
            return Err(Error::setting("size", format!("{width}x{height} (each side 1 to 16384)")));
        }
        if self.spp == 0 {
            return Err(Error::setting("spp", "0 (at least one sample per pixel)"));
        }
        self.camera.validate()?;
        let m = CameraMatrices::new(self.camera, width, height);
        Ok(FrameUniform::new(self.camera, m, m, width, height, 0.0, (0, 0, 0)))
    }
}

/// The ray of pixel position `px` through `camera` (whose matrices `f` holds): from the eye along
/// the pinhole ray, or, through a lens with an aperture, from a point of the lens disc (uniform
/// over its area, drawn from `rng`) through the pinhole ray's point at the focus depth.
fn camera_ray(f: &FrameUniform, camera: &Camera, px: Vec2, rng: &mut ChaCha8Rng) -> (Vec3, Vec3) {
    let to_world = |v: Vec3, w: f32| mat_mul(&f.inv_view, v.extend(w).to_array()).xyz();
    let near = view_position(f, px, 0.0);
    let lens = camera.lens;
    if !lens.blurs() {
        let dir = to_world(view_position(f, px, 1.0) - near, 0.0).normalize();
        return (to_world(near, 1.0), dir);
    }
    let focus = to_world(view_position(f, px, lens.focus), 1.0);
    let (u1, u2): (f32, f32) = (rng.random(), rng.random());
    let (r, phi) = (lens.radius * u1.sqrt(), 2.0 * PI * u2);
    let origin = to_world(Vec3::new(r * phi.cos(), r * phi.sin(), 0.0), 1.0);
    (origin, (focus - origin).normalize())
}

/// A point on the unit hemisphere around `n`, cosine distributed, from two uniform numbers.
fn cosine_direction(n: Vec3, u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let (t, b) = n.any_orthonormal_pair();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u.x).max(0.0).sqrt()).normalize()
}

impl Tracer {
    /// Builds the BVH of `scene` (which must be valid: see [`Scene::validate`]).
    pub fn new(scene: &Scene) -> Result<Tracer> {
        scene.validate()?;
        let triangles: Vec<Triangle> = scene
            .triangles
            .iter()
            .map(|t| {
                let [v0, v1, v2] = t.map(|i| Vec3A::from(scene.positions[i as usize]));
                Triangle { v0, v1, v2 }
            })
            .collect();
        let single_sided = scene
            .triangle_materials
            .iter()
            .map(|m| scene.materials.get(*m as usize).is_none_or(|m| !m.double_sided))
            .collect();
        let (lo, hi) = scene
            .positions
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let scale = (hi - lo).length().max(1e-6);
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &triangles,
            obvhs::BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let alpha: Vec<AlphaMode> = scene
            .triangle_materials
            .iter()
            .map(|m| scene.materials.get(*m as usize).map_or(AlphaMode::Opaque, |m| m.alpha_mode))
            .collect();
        let translucent =
            alpha.iter().any(|a| *a != AlphaMode::Opaque).then(|| Box::new(scene.clone()));
        Ok(Tracer { bvh, triangles, single_sided, scale, alpha, translucent })
    }

    /// Whether some triangle is blended (the full image then traces its primary rays through
    /// them).
    fn blends(&self) -> bool {
        self.alpha.contains(&AlphaMode::Blend)
    }

    /// The opacity of triangle `index` at `point` on it.
    fn opacity_at(&self, index: usize, point: Vec3) -> f32 {
        let Some(scene) = self.translucent.as_deref() else { return 1.0 };
        let tri = scene.triangles[index].map(|i| i as usize);
        let [a, b, c] = tri.map(|i| scene.positions[i]);
        let bary = plane_barycentrics(a, b, c, point);
        let m = &scene.materials[scene.triangle_materials[index] as usize];
        crate::cpu::resolve::material_opacity(m, &crate::cpu::resolve::Corners { scene, tri, bary })
    }

    /// Whether a ray meets triangle `index` at `point`: a masked surface where its opacity
    /// reaches the cutoff; a blended one never without `key` (the opaque scene), else with
    /// probability equal to its opacity (stochastic transparency: a uniform number from `key`
    /// and the triangle, so each ray decides once per triangle).
    fn meets(&self, index: usize, point: Vec3, key: Option<u64>) -> bool {
        match (self.alpha[index], key) {
            (AlphaMode::Opaque, _) => true,
            (AlphaMode::Mask { cutoff }, _) => self.opacity_at(index, point) >= cutoff,
            (AlphaMode::Blend, None) => false,
            (AlphaMode::Blend, Some(key)) => {
                let u = (mix64(key ^ mix64(index as u64)) >> 40) as f32 / (1u64 << 24) as f32;
                u < self.opacity_at(index, point)
            }
        }
    }

    /// The nearest hit along `origin + t dir` for t in (tmin, tmax) on the opaque scene (masked
    /// surfaces where they are solid; blended ones not at all): triangle index and t. With
    /// `cull`, back faces of single-sided triangles are not hit (as the rasterizer culls them).
    pub fn closest(
        &self,
        origin: Vec3,
        dir: Vec3,
        range: (f32, f32),
        cull: bool,
    ) -> Option<(u32, f32)> {
        self.closest_through(origin, dir, range, cull, None)
    }

    /// [`closest`](Tracer::closest), blended surfaces met with probability equal to their
    /// opacity when `key` is given (a number the caller draws per ray).
    pub fn closest_through(
        &self,
        origin: Vec3,
        dir: Vec3,
        (tmin, tmax): (f32, f32),
        cull: bool,
        key: Option<u64>,
    ) -> Option<(u32, f32)> {
        let ray = Ray::new(origin.into(), dir.into(), tmin, tmax);
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(ray, &mut hit, |ray, id| {
            let index = self.bvh.primitive_indices[id] as usize;
            let tri = &self.triangles[index];
            if cull && self.single_sided[index] {
                let facing = (tri.v1 - tri.v0).cross(tri.v2 - tri.v0).dot(ray.direction);
                if facing >= 0.0 {
                    return f32::INFINITY;
                }
            }
            let t = tri.intersect(ray);
            if t.is_finite()
                && self.alpha[index] != AlphaMode::Opaque
                && !self.meets(index, origin + dir * t, key)
            {
                return f32::INFINITY;
            }
            t
        });
        found.then(|| (self.bvh.primitive_indices[hit.primitive_id as usize], hit.t))
    }

    /// The layer-0 surface at pixel (x, y) as the G-buffer would hold it (default: none).
    pub fn primary(&self, f: &FrameUniform, scene: &Scene, x: u32, y: u32) -> GSample {
        let px = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let a = view_position(f, px, 0.0);
        let b = view_position(f, px, 1.0) - a;
        let to_world = |v: Vec3, w: f32| mat_mul(&f.inv_view, v.extend(w).to_array()).xyz();
        let origin = to_world(a, 1.0);
        // b advances the view depth by 1 per unit, so t along it is the view depth.
        let dir = to_world(b, 0.0);
        // What lies nearer than the near plane is clipped away, as the rasterizer clips it.
        let near = if f.ortho != 0 { f.near } else { f.near.max(0.0) };
        match self.closest(origin, dir, (near, f32::INFINITY), true) {
            Some((id, depth)) => {
                crate::cpu::resolve::resolve_pixel(f, scene, vis_pack(depth, id), x, y)
            }
            _ => GSample::default(),
        }
    }

    /// World-space ambient obscurance with the obscurance kernel's radius and falloff:
    ///
    /// ```text
    /// AV = clamp(1 - intensity * (1/pi) * integral over the hemisphere of
    ///             max(1 - d(w)^2 / r^2, 0) cos(theta) dw, 0, 1)
    /// ```
    ///
    /// with d(w) the distance to the first surface in direction w (any face; nothing: no
    /// obscurance). It is estimated with `spp` cosine-distributed rays per pixel, so each ray
    /// contributes its falloff alone. The kernel's bias beta (a guard against self-occlusion on
    /// tessellated curves, a screen-space artefact) has no place here. `progress` is called once
    /// per finished row.
    pub fn ambient_obscurance(
        &self,
        scene: &Scene,
        shot: &Shot,
        ao: &AoSettings,
        progress: &(dyn Fn() + Sync),
    ) -> Result<TruthImage> {
        let f = shot.frame()?;
        ao.validate()?;
        let spp = shot.spp;
        let r2 = ao.radius * ao.radius;
        let eps = 1e-5 * self.scale;
        self.per_pixel(&f, scene, shot.seed, progress, |s, point, _, rng| {
            let origin = point + s.normal * eps;
            let (mean, se) = sample_mean(spp, || {
                let u = Vec2::new(rng.random(), rng.random());
                let w = cosine_direction(s.normal, u);
                Vec3::splat(match self.closest(origin, w, (0.0, ao.radius), false) {
                    Some((_, d)) => (1.0 - d * d / r2).max(0.0),
                    None => 0.0,
                })
            });
            let av = (Vec3::ONE - ao.intensity * mean).clamp(Vec3::ZERO, Vec3::ONE);
            Some((av, ao.intensity * se))
        })
    }
}

/// What a ray sees where it hits a triangle: the shading normal (facing the ray's origin), the
/// material's diffuse albedo (times 1 - metallic), emission, and what the BRDF and the mirror
/// term need.
struct Surface {
    normal: Vec3,
    diffuse: Vec3,
    emission: Vec3,
    base_color: Vec3,
    roughness: f32,
    metallic: f32,
    reflectivity: f32,
    /// Scales the indirect light the surface reflects diffusely (the occlusion texture).
    occlusion: f32,
}

impl Surface {
    /// The surface a G-buffer sample describes.
    fn of(s: &GSample) -> Surface {
        Surface {
            normal: s.normal,
            diffuse: s.base_color * (1.0 - s.metallic),
            emission: s.emissive,
            base_color: s.base_color,
            roughness: s.roughness,
            metallic: s.metallic,
            reflectivity: s.reflectivity,
            occlusion: s.occlusion,
        }
    }
}

/// What light reaches the scene: its lights, and the sky that rays leaving it see.
struct Lighting<'a> {
    lights: Vec<GpuLight>,
    ambient: Vec3,
    environment: Option<&'a Environment>,
}

impl Lighting<'_> {
    fn sky(&self, d: Vec3) -> Vec3 {
        self.environment.map_or(self.ambient, |e| e.sample(d))
    }
}

/// The mirror direction of `d` about the unit normal `n`.
fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// A direction of the glossy lobe a surface of `roughness` (normal `n`) reflects the viewer's
/// direction `v` into: the mirror direction for roughness 0, else one visible-normal sample of
/// GGX with alpha = roughness^2 ([`lobe_direction`]).
fn lobe(n: Vec3, v: Vec3, roughness: f32, rng: &mut ChaCha8Rng) -> Vec3 {
    let alpha = roughness * roughness;
    if alpha > 0.0 {
        lobe_direction(n, v, alpha, Vec2::new(rng.random(), rng.random()))
    } else {
        reflect(-v, n)
    }
}

/// The unit direction from world point `point` towards the camera of `f`.
/// How far a primary hit is moved back towards the eye, relative to the scene's size: far above
/// the rounding of a reconstructed point (about 1e-7 of it), so that the point lies in front of
/// any surface it touches for views up to 89.4 degrees from that surface's normal, and far below
/// any radius an estimate is taken over.
const PULL_BACK: f32 = 1e-4;

fn towards_eye(f: &FrameUniform, point: Vec3) -> Vec3 {
    if f.ortho != 0 {
        return mat_mul(&f.inv_view, [0.0, 0.0, 1.0, 0.0]).xyz().normalize();
    }
    (mat_mul(&f.inv_view, [0.0, 0.0, 0.0, 1.0]).xyz() - point).normalize()
}

impl Tracer {
    fn surface(&self, scene: &Scene, id: u32, point: Vec3, dir: Vec3) -> Surface {
        let [i0, i1, i2] = scene.triangles[id as usize].map(|i| i as usize);
        let (a, b, c) = (scene.positions[i0], scene.positions[i1], scene.positions[i2]);
        let bary = plane_barycentrics(a, b, c, point);
        let geo = (b - a).cross(c - a).normalize_or(-dir);
        let interp =
            scene.normals[i0] * bary.x + scene.normals[i1] * bary.y + scene.normals[i2] * bary.z;
        let mut normal = interp.normalize_or(geo);
        let at = crate::cpu::resolve::Corners { scene, tri: [i0, i1, i2], bary };
        let m = scene.triangle_materials[id as usize];
        let material = scene.materials.get(m as usize);
        if let Some(material) = material {
            normal = crate::cpu::resolve::normal_mapped(material, &at, normal);
        }
        if geo.dot(dir) > 0.0 {
            normal = -normal;
        }
        if normal.dot(dir) > 0.0 {
            // An interpolated normal facing away from the ray: use the face.
            normal = if geo.dot(dir) > 0.0 { -geo } else { geo };
        }
        let Some(material) = material else {
            return Surface {
                normal,
                diffuse: Vec3::ZERO,
                emission: Vec3::ZERO,
                base_color: Vec3::ZERO,
                roughness: 1.0,
                metallic: 0.0,
                reflectivity: 0.0,
                occlusion: 1.0,
            };
        };
        let at = crate::cpu::resolve::material_at(material, &at);
        Surface {
            normal,
            diffuse: at.base_color * (1.0 - at.metallic),
            emission: at.emissive,
            base_color: at.base_color,
            roughness: at.roughness,
            metallic: at.metallic,
            reflectivity: at.reflectivity,
            occlusion: at.occlusion,
        }
    }

    /// Radiance the lights send from `s` at `point` towards `v` through the full BRDF (Lambert
    /// and GGX, as the direct pass), with shadow rays instead of shadow maps.
    fn direct_radiance(
        &self,
        lights: &[GpuLight],
        s: &Surface,
        point: Vec3,
        v: Vec3,
        rng: &mut ChaCha8Rng,
    ) -> Vec3 {
        let origin = point + s.normal * (1e-5 * self.scale);
        let mut sum = Vec3::ZERO;
        for light in lights {
            let (e, l) = crate::cpu::direct::light_at(light, point);
            let nl = s.normal.dot(l);
            if nl <= 0.0
                || e.max_element() <= 0.0
                || !self.unoccluded(light, origin, l, Some(rng.random()))
            {
                continue;
            }
            let brdf =
                crate::cpu::direct::brdf(s.normal, v, l, s.base_color, s.roughness, s.metallic);
            sum += brdf * e * nl;
        }
        sum
    }

    /// Whether nothing lies between `origin` and `light` along the unit direction `l` (blended
    /// surfaces let the light through stochastically with `key`, always without).
    fn unoccluded(&self, light: &GpuLight, origin: Vec3, l: Vec3, key: Option<u64>) -> bool {
        let reach = if light.kind == 0 {
            f32::INFINITY
        } else {
            (Vec3::from(light.position) - origin).length()
        };
        self.closest_through(origin, l, (0.0, reach), false, key).is_none()
    }

    /// Radiance arriving at `origin` from the unit direction `w`: the sky's where nothing is
    /// hit, else what the first surface sends back ([`Tracer::outgoing`]).
    fn radiance(
        &self,
        scene: &Scene,
        light: &Lighting,
        origin: Vec3,
        w: Vec3,
        depth: u32,
        rng: &mut ChaCha8Rng,
    ) -> Vec3 {
        let key = Some(rng.random());
        let Some((id, t)) = self.closest_through(origin, w, (0.0, f32::INFINITY), false, key)
        else {
            return light.sky(w);
        };
        let hit = origin + w * t;
        let surface = self.surface(scene, id, hit, w);
        self.outgoing(scene, light, &surface, hit, -w, depth, rng)
    }

    /// Radiance leaving surface `s` at `point` towards `v`, in the renderer's material model:
    /// emission, the lights through the BRDF, and while `depth` > 0 one cosine-distributed
    /// diffuse bounce (albedo times the radiance it brings: the cosine and 1/pi cancel with the
    /// sampling density) plus reflectivity times the radiance along one direction of the glossy
    /// lobe (the mirror direction for roughness 0; [`lobe`]), each traced on with `depth - 1`.
    #[expect(clippy::too_many_arguments, reason = "a path's state, spelled out")]
    fn outgoing(
        &self,
        scene: &Scene,
        light: &Lighting,
        s: &Surface,
        point: Vec3,
        v: Vec3,
        depth: u32,
        rng: &mut ChaCha8Rng,
    ) -> Vec3 {
        let mut out = s.emission + self.direct_radiance(&light.lights, s, point, v, rng);
        if depth == 0 {
            return out;
        }
        let origin = point + s.normal * (1e-5 * self.scale);
        if s.diffuse.max_element() > 0.0 {
            let w = cosine_direction(s.normal, Vec2::new(rng.random(), rng.random()));
            // The material's occlusion texture dims the indirect light it reflects (glTF).
            out += s.diffuse * s.occlusion * self.radiance(scene, light, origin, w, depth - 1, rng);
        }
        if s.reflectivity > 0.0 {
            let r = lobe(s.normal, v, s.roughness, rng);
            let tint = reflectance(s.reflectivity, s.base_color, s.metallic);
            out += tint * self.radiance(scene, light, origin, r, depth - 1, rng);
        }
        out
    }

    /// Irradiance the lights deliver at `point` (normal `n`), with shadow rays.
    fn direct_irradiance(&self, lights: &[GpuLight], point: Vec3, n: Vec3) -> Vec3 {
        let origin = point + n * (1e-5 * self.scale);
        let mut sum = Vec3::ZERO;
        for light in lights {
            let (e, l) = crate::cpu::direct::light_at(light, point);
            let nl = n.dot(l);
            if nl > 0.0 && e.max_element() > 0.0 && self.unoccluded(light, origin, l, None) {
                sum += e * nl;
            }
        }
        sum
    }

    /// Diffuse indirect irradiance by path tracing, the quantity the radiosity pass estimates:
    ///
    /// ```text
    /// E(X) = integral over the hemisphere of L(w) cos(theta) dw,
    /// ```
    ///
    /// where L is the outgoing diffuse radiance of the first surface in direction w: its emission
    /// plus its diffuse albedo (times 1 - metallic) / pi times the light arriving there, from
    /// the lights (with shadow rays) and, for `bounces` > 1, from further surfaces, recursively,
    /// up to `bounces` surfaces along a path. Directions that leave the scene bring nothing (the
    /// sky is the ambient term's). Cosine-distributed paths, `spp` per pixel, so a path's
    /// estimate is pi times the radiance it carries back. Specular reflection on the way is not
    /// followed (the radiosity pass gathers diffuse light).
    pub fn indirect(
        &self,
        scene: &Scene,
        shot: &Shot,
        bounces: u32,
        progress: &(dyn Fn() + Sync),
    ) -> Result<TruthImage> {
        let f = shot.frame()?;
        if bounces == 0 {
            return Err(Error::setting("bounces", "0 (at least one surface along a path)"));
        }
        let spp = shot.spp;
        let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::new).collect();
        let eps = 1e-5 * self.scale;
        self.per_pixel(&f, scene, shot.seed, progress, |s, point, _, rng| {
            Some(sample_mean(spp, || {
                let mut radiance = Vec3::ZERO;
                let mut throughput = Vec3::ONE;
                let (mut origin, mut normal) = (point + s.normal * eps, s.normal);
                for bounce in 0..bounces {
                    let u = Vec2::new(rng.random(), rng.random());
                    let w = cosine_direction(normal, u);
                    let Some((id, t)) = self.closest(origin, w, (0.0, f32::INFINITY), false) else {
                        break;
                    };
                    let hit = origin + w * t;
                    let surface = self.surface(scene, id, hit, w);
                    let e = self.direct_irradiance(&lights, hit, surface.normal);
                    radiance += throughput * (surface.emission + surface.diffuse / PI * e);
                    throughput *= surface.diffuse * surface.occlusion;
                    if bounce + 1 == bounces || throughput.max_element() <= 0.0 {
                        break;
                    }
                    (origin, normal) = (hit + surface.normal * eps, surface.normal);
                }
                radiance * PI
            }))
        })
    }

    /// Reflections, the quantity the reflection pass estimates: at every pixel whose surface
    /// reflects, its reflectance times the mean radiance arriving over its glossy lobe,
    ///
    /// ```text
    /// R(X) = reflectivity * mix(1, base colour, metallic) * E[L(X, l)],
    /// l = the reflection of v about a GGX visible normal
    /// ```
    ///
    /// (a metal tints what it reflects by its base colour, the F0 of its specular BRDF:
    /// [`reflectance`])
    ///
    /// (alpha = roughness^2, sampled as Heitz 2018, a direction below the surface mirrored above
    /// it: [`lobe_direction`]; the mirror direction `reflect(-v, n)` for roughness 0), where L is the sky's radiance (`environment`, else the scene's ambient) if the ray leaves
    /// the scene, else the radiance the surface it hits sends back ([`Tracer::full`]'s, with
    /// `bounces` more surfaces along each path). Pixels that do not reflect are not part of the
    /// image (not visible).
    pub fn reflections(
        &self,
        scene: &Scene,
        shot: &Shot,
        environment: Option<&Environment>,
        bounces: u32,
        progress: &(dyn Fn() + Sync),
    ) -> Result<TruthImage> {
        let f = shot.frame()?;
        let spp = shot.spp;
        let lighting = self.lighting(scene, environment);
        let eps = 1e-5 * self.scale;
        self.per_pixel(&f, scene, shot.seed, progress, |s, point, _, rng| {
            if s.reflectivity <= 0.0 {
                return None;
            }
            let v = towards_eye(&f, point);
            let origin = point + s.normal * eps;
            let tint = reflectance(s.reflectivity, s.base_color, s.metallic);
            Some(sample_mean(spp, || {
                let r = lobe(s.normal, v, s.roughness, rng);
                tint * self.radiance(scene, &lighting, origin, r, bounces, rng)
            }))
        })
    }

    /// The full image, the quantity the composite estimates: the radiance each layer-0 surface
    /// sends to the camera, with the same lights, materials and sky (`environment`, else the
    /// scene's ambient) by path tracing: emission, the lights through the BRDF with shadow rays,
    /// diffuse interreflection and glossy reflection, up to `bounces` surfaces after the first
    /// along a path (diffuse paths cosine distributed, one per sample; a reflective surface adds
    /// a branch along one direction of its lobe).
    /// Pixels without a surface are not part of the image.
    ///
    /// Through a camera lens with an aperture ([`Lens`](crate::scene::Lens)) each sample is a
    /// ray from a point of the lens disc (uniform over its area) through the pixel's point on the
    /// focus plane (at view depth `focus` on the pinhole ray), traced to whatever it meets: the
    /// thin-lens image the depth-of-field pass estimates (on the pixels whose pinhole ray meets a
    /// surface).
    pub fn full(
        &self,
        scene: &Scene,
        shot: &Shot,
        environment: Option<&Environment>,
        bounces: u32,
        progress: &(dyn Fn() + Sync),
    ) -> Result<TruthImage> {
        self.full_in_motion(scene, shot, None, environment, bounces, progress)
    }

    /// [`full`](Tracer::full) over an open shutter: each sample is taken at an instant of the
    /// shutter, through the camera moved linearly (eye, target and up) from the one before to
    /// the shot's, among the geometry as it stood then: the image the motion-blur pass
    /// estimates (on the pixels whose ray at the shot's instant meets a surface). Without moving
    /// geometry the instants spread uniformly over the shutter; with it they are the
    /// [`SHUTTER_INSTANTS`] midpoints of equal parts of it, each with its own tracer of the
    /// vertices moved linearly (normals as they are: exact for translations).
    pub fn full_in_motion(
        &self,
        scene: &Scene,
        shot: &Shot,
        motion: Option<&Shutter<'_>>,
        environment: Option<&Environment>,
        bounces: u32,
        progress: &(dyn Fn() + Sync),
    ) -> Result<TruthImage> {
        let f = shot.frame()?;
        let instants = match motion {
            Some(m) => m.instants(scene)?,
            None => Vec::new(),
        };
        let spp = shot.spp;
        let lighting = self.lighting(scene, environment);
        let camera = shot.camera;
        let (w, h) = shot.size;
        self.per_pixel(&f, scene, shot.seed, progress, |s, point, (x, y), rng| {
            if motion.is_none() && !camera.lens.blurs() && !self.blends() {
                let surface = Surface::of(s);
                let v = towards_eye(&f, point);
                return Some(sample_mean(spp, || {
                    self.outgoing(scene, &lighting, &surface, point, v, bounces, rng)
                }));
            }
            let px = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            Some(sample_mean(spp, || {
                // The instant of this sample: the camera then and the geometry as it stood.
                let (mut tracer, mut at_scene, mut t) = (self, scene, 1.0);
                if let Some(m) = motion {
                    if instants.is_empty() {
                        t = 1.0 - m.open * rng.random::<f32>();
                    } else {
                        let k = rng.random_range(0..instants.len());
                        (t, tracer, at_scene) = (instants[k].0, &instants[k].1, &instants[k].2);
                    }
                }
                let moved;
                let (at, frame) = match motion {
                    Some(m) => {
                        let before = m.before;
                        moved = Camera {
                            eye: before.eye.lerp(camera.eye, t),
                            target: before.target.lerp(camera.target, t),
                            up: before.up.lerp(camera.up, t),
                            ..camera.clone()
                        };
                        let m = CameraMatrices::new(&moved, w, h);
                        (&moved, FrameUniform::new(&moved, m, m, w, h, 0.0, (0, 0, 0)))
                    }
                    None => (camera, f),
                };
                let (origin, dir) = camera_ray(&frame, at, px, rng);
                tracer.radiance(at_scene, &lighting, origin, dir, bounces, rng)
            }))
        })
    }

    fn lighting<'a>(&self, scene: &Scene, environment: Option<&'a Environment>) -> Lighting<'a> {
        Lighting {
            lights: scene.lights.iter().map(GpuLight::new).collect(),
            ambient: scene.ambient,
            environment,
        }
    }

    /// Runs `estimate(layer-0 sample, its world point, its pixel, its sample stream)` for every
    /// pixel in
    /// parallel and gathers mean and standard error (`None`: the effect has no value there, and
    /// the pixel counts as not visible).
    fn per_pixel(
        &self,
        f: &FrameUniform,
        scene: &Scene,
        seed: u64,
        progress: &(dyn Fn() + Sync),
        estimate: impl Fn(&GSample, Vec3, (u32, u32), &mut ChaCha8Rng) -> Option<(Vec3, Vec3)> + Sync,
    ) -> Result<TruthImage> {
        let (width, height) = (f.width, f.height);
        let rows: Vec<Vec<(Vec3, Vec3, bool)>> = (0..height)
            .into_par_iter()
            .map(|y| {
                let row = (0..width)
                    .map(|x| {
                        let s = self.primary(f, scene, x, y);
                        if s.depth.is_nan() || s.depth <= 0.0 {
                            return (Vec3::ZERO, Vec3::ZERO, false);
                        }
                        let px = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        let view = view_position(f, px, s.depth);
                        let point = mat_mul(&f.inv_view, view.extend(1.0).to_array()).xyz();
                        // Back along the primary ray into the free space it crossed: a point on
                        // a crease, rounded to the far side of the neighbouring surface, would
                        // start every secondary ray inside it. The offset along the normal that
                        // each estimator adds cannot do this (it runs parallel to that surface).
                        let point = point + towards_eye(f, point) * (PULL_BACK * self.scale);
                        let mut rng = pixel_rng(seed, x, y, width);
                        match estimate(&s, point, (x, y), &mut rng) {
                            Some((mean, se)) => (mean, se, true),
                            None => (Vec3::ZERO, Vec3::ZERO, false),
                        }
                    })
                    .collect();
                progress();
                row
            })
            .collect();
        let flat: Vec<_> = rows.into_iter().flatten().collect();
        Ok(TruthImage {
            width,
            height,
            value: flat.iter().map(|v| v.0).collect(),
            stderr: flat.iter().map(|v| v.1).collect(),
            visible: flat.iter().map(|v| v.2).collect(),
        })
    }
}

/// Mean and standard error of `n` samples drawn from `sample`.
fn sample_mean(n: u32, mut sample: impl FnMut() -> Vec3) -> (Vec3, Vec3) {
    let (mut sum, mut sum2) = (Vec3::ZERO, Vec3::ZERO);
    for _ in 0..n {
        let x = sample();
        sum += x;
        sum2 += x * x;
    }
    let n = n as f32;
    let mean = sum / n;
    if n < 2.0 {
        return (mean, Vec3::ZERO);
    }
    let var = ((sum2 / n - mean * mean) * (n / (n - 1.0))).max(Vec3::ZERO);
    (mean, (var / n).sqrt())
}

/// The sample stream of pixel (x, y): the same on every run and thread count.
fn pixel_rng(seed: u64, x: u32, y: u32, width: u32) -> ChaCha8Rng {
    let index = u64::from(y) * u64::from(width) + u64::from(x);
    ChaCha8Rng::seed_from_u64(seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}
