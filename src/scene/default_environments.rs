//! The built-in environments that need no file (`vkvcm render --env studio|sky`): a
//! neutral studio and an analytic daylight sky with a sun, generated on the CPU as
//! equirectangular maps ([`EnvironmentMap`], docs/environment.md's texel convention), so
//! that every estimator samples and evaluates them exactly as a map read from a file.
//!
//! Both are normalised so that a white Lambertian surface facing up (+Y) under them has
//! radiance 1, as under the uniform white sky of radiance 1: switching between them keeps
//! the exposure.

use anyhow::{bail, Result};
use glam::{DVec3, Vec3};

use super::environment::EnvironmentMap;

/// The studio's default size: its lights are at least 15 degrees wide, 1.4 degrees a texel.
pub const STUDIO_SIZE: (u32, u32) = (256, 128);
/// The sky's default size: 0.35 degrees a texel, so that the sun is a few texels wide.
pub const SKY_SIZE: (u32, u32) = (1024, 512);

/// The unit direction of texel (i, j) of a W x H map (docs/environment.md: u = (i + 1/2) /
/// W, v = j / (H - 1); u = atan2(x, -z) / 2 pi, v = acos(y) / pi).
fn texel_direction(i: u32, j: u32, w: u32, h: u32) -> DVec3 {
    let u = (i as f64 + 0.5) / w as f64;
    let v = j as f64 / (h - 1) as f64;
    direction_at(u, v)
}

fn direction_at(u: f64, v: f64) -> DVec3 {
    let (theta, phi) = (v * std::f64::consts::PI, u * std::f64::consts::TAU);
    DVec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// Irradiance (per channel) on a surface facing +Y under `texels` (a W x H map), by the
/// map's own quadrature: each texel stands for a cell of solid angle
/// (2 pi / W) (pi / (H - 1)) sin(theta).
pub fn upward_irradiance(texels: &[[f32; 3]], w: u32, h: u32) -> DVec3 {
    let cell = std::f64::consts::TAU / w as f64 * std::f64::consts::PI / (h - 1) as f64;
    let mut e = DVec3::ZERO;
    for j in 0..h {
        for i in 0..w {
            let d = texel_direction(i, j, w, h);
            if d.y > 0.0 {
                let sin_theta = (1.0 - d.y * d.y).max(0.0).sqrt();
                e += DVec3::from(texels[(j * w + i) as usize].map(f64::from)) * d.y * cell * sin_theta;
            }
        }
    }
    e
}

/// Scales `texels` so that [`upward_irradiance`]'s luminance is pi (a white diffuse
/// surface facing up then has radiance 1).
fn normalise(texels: &mut [[f32; 3]], w: u32, h: u32) {
    let e = upward_irradiance(texels, w, h);
    let lum = 0.2126 * e.x + 0.7152 * e.y + 0.0722 * e.z;
    let s = (std::f64::consts::PI / lum) as f32;
    for t in texels {
        *t = t.map(|c| c * s);
    }
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A studio's soft light: a disc of angular radius `radius_deg` around `towards` with a
/// soft edge, of grey radiance `radiance`.
struct Softbox {
    towards: DVec3,
    radius_deg: f64,
    radiance: f64,
}

/// A neutral studio of the kind glTF viewers light models with (three.js's
/// RoomEnvironment, the Khronos sample viewer's neutral IBL): a grey room, darker below
/// than above, with four soft area lights (a key light front right, a fill light left, a
/// light overhead and a rim light behind), all grey, so that a model's colours are its own
/// and its metals have highlights and a horizon to reflect. Values chosen by eye, not
/// measured; deterministic.
pub fn studio(width: u32, height: u32) -> Result<EnvironmentMap> {
    let lights = [
        Softbox { towards: DVec3::new(0.6, 0.7, 0.8), radius_deg: 18.0, radiance: 6.0 },
        Softbox { towards: DVec3::new(-0.8, 0.3, 0.5), radius_deg: 25.0, radiance: 2.0 },
        Softbox { towards: DVec3::Y, radius_deg: 30.0, radiance: 3.0 },
        Softbox { towards: DVec3::new(0.2, 0.5, -1.0), radius_deg: 15.0, radiance: 5.0 },
    ];
    check_size("studio", width, height)?;
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for j in 0..height {
        for i in 0..width {
            let d = texel_direction(i, j, width, height);
            // Floor 0.2, walls and ceiling 0.5, blended across the horizon.
            let mut l = 0.2 + 0.3 * smoothstep(-0.15, 0.15, d.y);
            for b in &lights {
                let r = b.radius_deg.to_radians();
                let c = d.dot(b.towards.normalize());
                l += b.radiance * smoothstep((1.15 * r).cos(), (0.85 * r).cos(), c);
            }
            texels.push([l as f32; 3]);
        }
    }
    normalise(&mut texels, width, height);
    EnvironmentMap::new("studio", width, height, texels)
}

fn check_size(what: &str, width: u32, height: u32) -> Result<()> {
    if width < 8 || height < 4 {
        bail!("the {what} environment needs at least 8 x 4 texels, not {width} x {height}");
    }
    Ok(())
}

/// Where the sun is and how hazy the air: `vkvcm render --env sky`'s options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyParameters {
    /// Degrees from +Z towards +X (the map's rotation turns it further).
    pub sun_azimuth_deg: f32,
    /// Degrees above the horizon, in (0, 90].
    pub sun_elevation_deg: f32,
    /// Preetham's turbidity T, in [2, 10]: 2 a very clear sky, 10 haze.
    pub turbidity: f32,
}

impl Default for SkyParameters {
    fn default() -> Self {
        SkyParameters { sun_azimuth_deg: 30.0, sun_elevation_deg: 45.0, turbidity: 3.0 }
    }
}

/// The sun's angular radius: about twice the real sun's 0.27 degrees, so that the default
/// map (0.35 degrees a texel) resolves its disc.
const SUN_RADIUS_DEG: f64 = 0.5;
/// The sun's irradiance at normal incidence, as a multiple of the sky's on a horizontal
/// surface (a clear sky's diffuse part is 10-20% of the total at mid elevations).
const SUN_OVER_SKY: f64 = 8.0;
/// The ground below the horizon: a grey Lambertian plane of this albedo lit by the sky and
/// the sun.
const GROUND_ALBEDO: f64 = 0.3;

/// Perez et al.'s luminance distribution, F(theta, gamma) = (1 + A e^(B / cos theta))
/// (1 + C e^(D gamma) + E cos^2 gamma), with coefficients `k` = [A, B, C, D, E].
fn perez(k: [f64; 5], cos_theta: f64, gamma: f64) -> f64 {
    let cos_gamma = gamma.cos();
    (1.0 + k[0] * (k[1] / cos_theta.max(1e-3)).exp())
        * (1.0 + k[2] * (k[3] * gamma).exp() + k[4] * cos_gamma * cos_gamma)
}

/// An analytic daylight sky: A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic
/// Model for Daylight", SIGGRAPH 1999 (Perez's distribution of luminance Y and
/// chromaticity x, y, with the paper's Appendix A.2 fits in turbidity and the zenith
/// values of its equations), converted from xyY to linear Rec. 709 RGB, plus a sun disc
/// of constant radiance ([`SUN_RADIUS_DEG`], [`SUN_OVER_SKY`]; white: Preetham's
/// sunlight spectrum through the atmosphere is not modelled) and a grey ground
/// ([`GROUND_ALBEDO`]). Deterministic.
pub fn sky(width: u32, height: u32, p: &SkyParameters) -> Result<EnvironmentMap> {
    check_size("sky", width, height)?;
    let t = p.turbidity as f64;
    if !(2.0..=10.0).contains(&t) {
        bail!("turbidity {t}: Preetham's model is fitted for 2 to 10");
    }
    if !(p.sun_elevation_deg > 0.0 && p.sun_elevation_deg <= 90.0) {
        bail!("sun elevation {} degrees: must be in (0, 90]", p.sun_elevation_deg);
    }
    if !p.sun_azimuth_deg.is_finite() {
        bail!("sun azimuth {}: must be a number of degrees", p.sun_azimuth_deg);
    }
    let (az, el) = ((p.sun_azimuth_deg as f64).to_radians(), (p.sun_elevation_deg as f64).to_radians());
    let sun = DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
    let theta_s = std::f64::consts::FRAC_PI_2 - el;
    let coefficients = [
        [0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251, 0.1206 * t - 2.5771, -0.0670 * t + 0.3703],
        [-0.0193 * t - 0.2592, -0.0665 * t + 0.0008, -0.0004 * t + 0.2125, -0.0641 * t - 0.8989, -0.0033 * t + 0.0452],
        [-0.0167 * t - 0.2608, -0.0950 * t + 0.0092, -0.0079 * t + 0.2102, -0.0441 * t - 1.6537, -0.0109 * t + 0.0529],
    ];
    let zenith = zenith_xyy(t, theta_s);
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for j in 0..height {
        for i in 0..width {
            let d = texel_direction(i, j, width, height);
            if d.y <= 0.0 {
                texels.push([0.0; 3]);
                continue;
            }
            let gamma = d.dot(sun).clamp(-1.0, 1.0).acos();
            let v: [f64; 3] = std::array::from_fn(|k| {
                zenith[k] * perez(coefficients[k], d.y, gamma) / perez(coefficients[k], 1.0, theta_s)
            });
            texels.push(xyy_to_rgb(v[1], v[2], v[0]).to_array());
        }
    }
    let e_sky = upward_irradiance(&texels, width, height);
    let e_sky_lum = 0.2126 * e_sky.x + 0.7152 * e_sky.y + 0.0722 * e_sky.z;
    add_sun(&mut texels, width, height, sun, SUN_OVER_SKY * e_sky_lum);
    // The ground reflects what reaches it: the sky's and the sun's irradiance.
    let e = upward_irradiance(&texels, width, height);
    let ground = (e * GROUND_ALBEDO / std::f64::consts::PI).as_vec3().to_array();
    for j in 0..height {
        for i in 0..width {
            if texel_direction(i, j, width, height).y <= 0.0 {
                texels[(j * width + i) as usize] = ground;
            }
        }
    }
    normalise(&mut texels, width, height);
    let source = format!(
        "sky (Preetham, turbidity {}, sun at azimuth {} and elevation {} degrees)",
        p.turbidity, p.sun_azimuth_deg, p.sun_elevation_deg
    );
    EnvironmentMap::new(&source, width, height, texels)
}

/// Preetham et al.'s zenith luminance Y (kcd/m^2) and chromaticity x, y for turbidity `t`
/// and the sun's zenith angle `theta_s` (the paper's Appendix A.2).
fn zenith_xyy(t: f64, theta_s: f64) -> [f64; 3] {
    let chi = (4.0 / 9.0 - t / 120.0) * (std::f64::consts::PI - 2.0 * theta_s);
    let y = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
    let (s, s2, s3) = (theta_s, theta_s * theta_s, theta_s * theta_s * theta_s);
    let t2 = t * t;
    let x = t2 * (0.00166 * s3 - 0.00375 * s2 + 0.00209 * s)
        + t * (-0.02903 * s3 + 0.06377 * s2 - 0.03202 * s + 0.00394)
        + (0.11693 * s3 - 0.21196 * s2 + 0.06052 * s + 0.25886);
    let yc = t2 * (0.00275 * s3 - 0.00610 * s2 + 0.00317 * s)
        + t * (-0.04214 * s3 + 0.08970 * s2 - 0.04153 * s + 0.00516)
        + (0.15346 * s3 - 0.26756 * s2 + 0.06670 * s + 0.26688);
    [y.max(0.0), x, yc]
}

/// CIE xyY to linear Rec. 709 RGB (D65), negative components clamped to 0.
fn xyy_to_rgb(x: f64, y: f64, lum: f64) -> Vec3 {
    let big_x = x * lum / y;
    let big_z = (1.0 - x - y) * lum / y;
    let r = 3.2406 * big_x - 1.5372 * lum - 0.4986 * big_z;
    let g = -0.9689 * big_x + 1.8758 * lum + 0.0415 * big_z;
    let b = 0.0557 * big_x - 0.2040 * lum + 1.0570 * big_z;
    DVec3::new(r, g, b).max(DVec3::ZERO).as_vec3()
}

/// Adds a sun disc of radius [`SUN_RADIUS_DEG`] around `sun` whose irradiance at normal
/// incidence is `irradiance`: each texel near it gets the sun's radiance times the part of
/// its cell the disc covers (8 x 8 samples), so that the disc's power does not depend on
/// where it falls between texels.
fn add_sun(texels: &mut [[f32; 3]], w: u32, h: u32, sun: DVec3, irradiance: f64) {
    let r = SUN_RADIUS_DEG.to_radians();
    let solid_angle = std::f64::consts::TAU * (1.0 - r.cos());
    let radiance = irradiance / solid_angle;
    // A texel's cell spans (i, j) +- half a texel; those within this angle of the sun may
    // touch the disc.
    let reach = r + std::f64::consts::PI / (h - 1) as f64 * 2.0 + std::f64::consts::TAU / w as f64;
    const N: u32 = 8;
    for j in 0..h {
        for i in 0..w {
            let d = texel_direction(i, j, w, h);
            if d.dot(sun).clamp(-1.0, 1.0).acos() > reach {
                continue;
            }
            let mut inside = 0;
            for a in 0..N {
                for b in 0..N {
                    let u = (i as f64 + (a as f64 + 0.5) / N as f64) / w as f64;
                    let v = ((j as f64 - 0.5 + (b as f64 + 0.5) / N as f64) / (h - 1) as f64).clamp(0.0, 1.0);
                    if direction_at(u, v).dot(sun) >= r.cos() {
                        inside += 1;
                    }
                }
            }
            if inside > 0 {
                let add = (radiance * inside as f64 / (N * N) as f64) as f32;
                let t = &mut texels[(j * w + i) as usize];
                *t = t.map(|c| c + add);
            }
        }
    }
}
