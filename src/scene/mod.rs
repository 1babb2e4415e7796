//! Scene description shared by the importer, the BVH builder and the renderers.
//!
//! Units and conventions: right-handed, y-up (glTF). Radiometric quantities are linear
//! RGB. Every light's meaning is stated on its variant.

use glam::Vec3;

/// A triangle in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Per-vertex shading normals (world space, unit length) when the source gives them.
    pub n: Option<[Vec3; 3]>,
    pub material: u32,
}

/// An analytic sphere (glTF extension `VKVCM_spheres`).
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
}

/// vkvcm's material model: a sum of components, each selected with probability
/// proportional to its luminance albedo (../shared/SCENES.md 2.4).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Lambertian reflectance.
    pub diffuse: Vec3,
    /// Normalised Phong lobe around the mirror direction: rho (n+2)/(2 pi) cos^n.
    pub phong: Vec3,
    pub phong_exponent: f32,
    /// Perfect specular reflectance (Fresnel-weighted when `ior >= 0`).
    pub mirror: Vec3,
    /// Index of refraction of a smooth dielectric; negative means "not a dielectric".
    pub ior: f32,
    /// Emitted radiance (W/(m^2 sr)) for area emitters; zero for non-emitters.
    pub emission: Vec3,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            diffuse: Vec3::ZERO,
            phong: Vec3::ZERO,
            phong_exponent: 1.0,
            mirror: Vec3::ZERO,
            ior: -1.0,
            emission: Vec3::ZERO,
        }
    }
}

/// Light sources. Lights are picked uniformly (probability 1/#lights) for emission and
/// next-event estimation, as in SmallVCM.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// One emitting triangle (index into `Scene::triangles`), Lambertian, one-sided: it
    /// emits on the side its geometric normal (p1-p0)x(p2-p0) points to.
    Area { triangle: u32, radiance: Vec3 },
    /// Isotropic point light; `intensity` in W/sr (glTF candela).
    Point { position: Vec3, intensity: Vec3 },
    /// Spot light; intensity in W/sr inside the inner cone, smooth falloff to the outer.
    Spot {
        position: Vec3,
        /// Unit direction the spot points to.
        direction: Vec3,
        intensity: Vec3,
        cos_inner: f32,
        cos_outer: f32,
    },
    /// Directional (sun) light; `direction` is the unit direction photons travel,
    /// `irradiance` in W/m^2 on a surface facing the light (glTF lux).
    Directional { direction: Vec3, irradiance: Vec3 },
    /// Constant environment radiance from every direction (extension `VKVCM_background`).
    Background { radiance: Vec3 },
}

/// Pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit up vector, orthogonal to `forward`.
    pub up: Vec3,
    /// Vertical field of view in radians (for a square image equal to the horizontal).
    pub yfov: f32,
}

/// What the importer skipped or could not represent; printed once per kind.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadReport {
    pub degenerate_triangles: usize,
    pub warnings: Vec<String>,
}

/// A scene ready for BVH construction and rendering.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub report: LoadReport,
}
