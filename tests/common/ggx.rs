//! A CPU model of the GGX lobe of glsl/bsdf.glsl (F = 1, height-correlated Smith), for
//! tests that check its energy against an independent quadrature.

use std::f64::consts::{FRAC_PI_2, PI};

/// GGX D(h) for cos(theta_h) = `ch`, width `a`.
pub fn ggx_d(ch: f64, a: f64) -> f64 {
    let a2 = a * a;
    let t = ch * ch * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith's Lambda for GGX at cos(theta) = `c`.
pub fn ggx_lambda(c: f64, a: f64) -> f64 {
    let tan2 = (1.0 - c * c).max(0.0) / (c * c);
    0.5 * ((1.0 + a * a * tan2).sqrt() - 1.0)
}

/// Directional albedo of the F = 1 GGX lobe at cos(theta_o) = `mu`: the integral of
/// f cos(theta_i) over the hemisphere, by a midpoint rule over the half vector with `nt` x
/// `np` cells (importance-free, so it checks the normalisation of D independently of
/// sampling). [`ggx_albedo_with`] with F = 1.
pub fn ggx_albedo(mu: f64, a: f64, nt: usize, np: usize) -> f64 {
    ggx_albedo_with(mu, a, nt, np, &|_| [1.0; 3])[0]
}

/// [`ggx_albedo`] per channel of the lobe whose Fresnel term is `fr(wo.h)`:
/// f cos_i dw_i = F D G2 / (4 cos_o cos_i) cos_i 4 (wo.h) dw_h.
pub fn ggx_albedo_with(mu: f64, a: f64, nt: usize, np: usize, fr: &dyn Fn(f64) -> [f64; 3]) -> [f64; 3] {
    let wo = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let mut sum = [0.0; 3];
    for i in 0..nt {
        // theta_h in [0, pi/2); substitute theta_h = atan(a tan(s)) to resolve narrow lobes.
        let s = (i as f64 + 0.5) / nt as f64 * FRAC_PI_2;
        let th = (a * s.tan()).atan();
        let dth_ds = a / (s.cos().powi(2) + a * a * s.sin().powi(2));
        let (st, ct) = (th.sin(), th.cos());
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
            let h = [st * phi.cos(), st * phi.sin(), ct];
            let oh = wo[0] * h[0] + wo[2] * h[2];
            let ci = 2.0 * oh * h[2] - wo[2];
            if oh <= 0.0 || ci <= 0.0 {
                continue;
            }
            let g2 = 1.0 / (1.0 + ggx_lambda(mu, a) + ggx_lambda(ci, a));
            let w = ggx_d(ct, a) * g2 / mu * oh * st * dth_ds * (FRAC_PI_2 / nt as f64) * (2.0 * PI / np as f64);
            let f = fr(oh);
            for k in 0..3 {
                sum[k] += w * f[k];
            }
        }
    }
    sum
}
