//! A CPU model, in f64, of KHR_materials_iridescence's Fresnel term as the extension's
//! implementation notes write it (Belcour & Barla 2017; glsl/lobes/iridescence.glsl is the
//! kernels'), and the directional albedo of the GGX lobe with it, for
//! tests/render_iridescence.rs.
#![allow(dead_code)]

use std::f64::consts::PI;

/// A thin film: iridescenceFactor, the film's IOR and thickness (nm).
#[derive(Clone, Copy, Debug)]
pub struct Film {
    pub factor: f64,
    pub ior: f64,
    pub thickness: f64,
}

fn schlick(f0: f64, c: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - c).powi(5)
}

/// The XYZ sensitivities' Fourier transform at optical path difference `opd` (nm), phase
/// `shift`, in linear Rec. 709 (the extension's evalSensitivity).
fn sensitivity(opd: f64, shift: [f64; 3]) -> [f64; 3] {
    let phase = 2.0 * PI * opd * 1e-9;
    let val = [5.4856e-13, 4.4201e-13, 5.2481e-13];
    let pos = [1.6810e+06, 1.7953e+06, 2.2084e+06];
    let var = [4.3278e+09, 9.3046e+09, 6.6121e+09];
    let mut xyz = [0.0; 3];
    for k in 0..3 {
        xyz[k] =
            val[k] * (2.0 * PI * var[k]).sqrt() * (pos[k] * phase + shift[k]).cos() * (-phase * phase * var[k]).exp();
    }
    xyz[0] += 9.7470e-14
        * (2.0 * PI * 4.5282e+09f64).sqrt()
        * (2.2399e+06 * phase + shift[0]).cos()
        * (-4.5282e+09 * phase * phase).exp();
    let xyz = xyz.map(|v| v / 1.0685e-7);
    // CIE XYZ to linear Rec. 709 (rows).
    let m =
        [[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560], [0.0556434, -0.2040259, 1.0572252]];
    m.map(|r| r[0] * xyz[0] + r[1] * xyz[1] + r[2] * xyz[2])
}

/// F_iridescence of `film` in air over a base of Schlick F0 `f0` at cosine `c`, before any
/// clamping: the Airy sum's mean and first two orders (the optical path difference with
/// the angle inside the film, as Belcour & Barla).
pub fn iridescence_unclamped(film: &Film, f0: [f64; 3], c: f64) -> [f64; 3] {
    let t = film.thickness;
    let s = (t / 0.03).clamp(0.0, 1.0);
    let n2 = 1.0 + (film.ior - 1.0) * s * s * (3.0 - 2.0 * s);
    let sin2 = (1.0 - c * c) / (n2 * n2);
    if sin2 >= 1.0 {
        return [1.0; 3];
    }
    let c2 = (1.0 - sin2).sqrt();
    let r12 = schlick(((n2 - 1.0) / (n2 + 1.0)).powi(2), c);
    let t121 = 1.0 - r12;
    let phi21 = if n2 < 1.0 { 0.0 } else { PI };
    let opd = 2.0 * n2 * t * c2;
    let mut out = [0.0; 3];
    let mut r23 = [0.0; 3];
    let mut phi = [0.0; 3];
    for k in 0..3 {
        let sf = f0[k].clamp(0.0, 0.9999).sqrt();
        let n3 = (1.0 + sf) / (1.0 - sf);
        r23[k] = schlick(((n3 - n2) / (n3 + n2)).powi(2), c2);
        phi[k] = phi21 + if n3 < n2 { PI } else { 0.0 };
    }
    let s1 = sensitivity(opd, phi);
    let s2 = sensitivity(2.0 * opd, phi.map(|p| 2.0 * p));
    for k in 0..3 {
        let r123 = (r12 * r23[k]).clamp(1e-5, 0.9999);
        let rs = t121 * t121 * r23[k] / (1.0 - r123);
        let c1 = (rs - t121) * r123.sqrt();
        let c2 = c1 * r123.sqrt();
        out[k] = r12 + rs + c1 * 2.0 * s1[k] + c2 * 2.0 * s2[k];
    }
    out
}

/// The Fresnel term of the kernels: mix(Schlick, F_iridescence clamped to [0, 1], factor).
pub fn fresnel(film: &Film, f0: [f64; 3], c: f64) -> [f64; 3] {
    let i = iridescence_unclamped(film, f0, c);
    let mut out = [0.0; 3];
    for k in 0..3 {
        let s = schlick(f0[k], c);
        out[k] = s + (i[k].clamp(0.0, 1.0) - s) * film.factor;
    }
    out
}

/// E_avg = 2 int_0^1 F(mu) mu dmu per channel by the midpoint rule in mu over `n` cells
/// (the kernels' rule with n = 16, glsl/lobes/iridescence.glsl).
pub fn fresnel_average(film: &Film, f0: f64, n: usize) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for k in 0..n {
        let mu = (k as f64 + 0.5) / n as f64;
        let f = fresnel(film, [f0; 3], mu);
        for c in 0..3 {
            sum[c] += 2.0 * f[c] * mu / n as f64;
        }
    }
    sum
}
