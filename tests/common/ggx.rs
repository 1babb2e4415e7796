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
/// f cos_i dw_i = F D G2 / (4 cos_o cos_i) cos_i 4 (wo.h) dw_h, over the half vectors whose
/// wi lies above the horizon: on the ring theta_h the azimuths with cos(phi) > b(theta_h) =
/// mu (1 - 2 cos^2 theta_h) / (2 cos theta_h sin theta_o sin theta_h) (b increases with
/// theta_h), the whole ring up to theta_full (b = -1), none past theta_max (b = 1). The
/// midpoint rule runs over smooth pieces only: per ring over the valid azimuths, and in
/// theta_h over [0, theta_full] and [theta_full, theta_max], each through a smoothstep
/// substitution that removes the square-root kinks at their ends, after theta_h =
/// atan(a tan(s)), which resolves narrow lobes. (Cutting at the horizon inside the cells
/// would leave an error of order 1 / n.)
pub fn ggx_albedo_with(mu: f64, a: f64, nt: usize, np: usize, fr: &dyn Fn(f64) -> [f64; 3]) -> [f64; 3] {
    let so = (1.0 - mu * mu).max(1e-24).sqrt();
    let lambda_o = ggx_lambda(mu, a);
    let bound = |th: f64| mu * (1.0 - 2.0 * th.cos().powi(2)) / (2.0 * th.cos() * so * th.sin());
    // b(theta) = target by bisection, in s = atan(tan(theta) / a).
    let s_where = |target: f64| {
        let (mut lo, mut hi) = (0.0f64, FRAC_PI_2);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if bound((a * mid.tan()).atan()) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let (s_full, s_max) = (s_where(-1.0), s_where(1.0));
    let mut sum = [0.0; 3];
    for (s0, s1) in [(0.0, s_full), (s_full, s_max)] {
        for i in 0..nt {
            let u = (i as f64 + 0.5) / nt as f64;
            let s = s0 + (s1 - s0) * u * u * (3.0 - 2.0 * u);
            let ds_du = (s1 - s0) * 6.0 * u * (1.0 - u);
            let th = (a * s.tan()).atan();
            let dth_ds = a / (s.cos().powi(2) + a * a * s.sin().powi(2));
            let (st, ct) = (th.sin(), th.cos());
            let phi_max = bound(th).clamp(-1.0, 1.0).acos();
            let ring = ggx_d(ct, a) / mu * st * dth_ds * ds_du / nt as f64 * (2.0 * phi_max / np as f64);
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * phi_max;
                let oh = so * st * phi.cos() + mu * ct;
                let ci = 2.0 * oh * ct - mu;
                if oh <= 0.0 || ci <= 0.0 {
                    continue;
                }
                let w = ring * oh / (1.0 + lambda_o + ggx_lambda(ci, a));
                let f = fr(oh);
                for k in 0..3 {
                    sum[k] += w * f[k];
                }
            }
        }
    }
    sum
}

/// The kernels' smallest GGX width (glsl/types.glsl MIN_GGX_ALPHA).
pub const MIN_GGX_ALPHA: f64 = vkvcm::render::gpu_types::MIN_GGX_ALPHA as f64;
/// The albedo table's size (src/render/ggx_albedo.rs): cosines (i / (N_MU - 1))^2 (crowded
/// at grazing angles, where Schlick's F and the masking change fastest) by roughnesses
/// r = j / (N_R - 1), width max(r^2, MIN_GGX_ALPHA).
pub const N_MU: usize = vkvcm::render::ggx_albedo::GGX_ALBEDO_MU;
pub const N_R: usize = vkvcm::render::ggx_albedo::GGX_ALBEDO_R;

/// The table's cosine at row `i` (at 0 the albedo's limit, taken at 1e-6).
pub fn table_cosine(i: usize) -> f64 {
    ((i as f64 / (N_MU - 1) as f64).powi(2)).max(1e-6)
}

/// The table's GGX width at column `j`.
pub fn table_alpha(j: usize) -> f64 {
    (j as f64 / (N_R - 1) as f64).powi(2).max(MIN_GGX_ALPHA)
}

/// The directional albedo of the GGX lobe with Schlick's F of F0 `f0` is f0 A + B, linear in
/// f0 (F = f0 (1 - s) + s, s = (1 - wo.h)^5): (A, B) at cos(theta_o) = `mu`, width `a`, by
/// [`ggx_albedo_with`]'s quadrature with `n` x `n` cells.
pub fn ggx_albedo_terms(mu: f64, a: f64, n: usize) -> [f64; 2] {
    let e = ggx_albedo_with(mu, a, n, n, &|oh| {
        let s = (1.0 - oh).powi(5);
        [1.0 - s, s, 0.0]
    });
    [e[0], e[1]]
}

/// The table by quadrature, rounded to 5 decimals as src/render/ggx_albedo.rs stores it:
/// (A, B) pairs row-major by roughness, N_MU cosines each.
pub fn ggx_albedo_table(n: usize) -> Vec<[f64; 2]> {
    let round = |x: f64| (x * 1e5).round() / 1e5;
    let mut t = Vec::with_capacity(N_MU * N_R);
    for j in 0..N_R {
        for i in 0..N_MU {
            let [a, b] = ggx_albedo_terms(table_cosine(i), table_alpha(j), n);
            t.push([round(a), round(b)]);
        }
    }
    t
}

/// The cosine-weighted averages 2 int_0^1 E(mu) mu dmu of `table`'s A and B per roughness,
/// exact for the interpolation the kernels do (linear in x = sqrt(mu) between rows:
/// 2 mu dmu = 4 x^3 dx), so that the diffuse lobe's normalisation 1 - E_avg is exactly
/// the integral of the 1 - E it is weighted by.
pub fn ggx_albedo_averages(table: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let h = 1.0 / (N_MU - 1) as f64;
    // int x^3 (x1 - x) / h dx and int x^3 (x - x0) / h dx over [x0, x1].
    let weights = |x0: f64, x1: f64| {
        let p = |x: f64| x1 * x.powi(4) / 4.0 - x.powi(5) / 5.0;
        let q = |x: f64| x.powi(5) / 5.0 - x0 * x.powi(4) / 4.0;
        ((p(x1) - p(x0)) / h, (q(x1) - q(x0)) / h)
    };
    table
        .chunks(N_MU)
        .map(|row| {
            let mut avg = [0.0; 2];
            for i in 0..N_MU - 1 {
                let (w0, w1) = weights(i as f64 * h, (i + 1) as f64 * h);
                for k in 0..2 {
                    avg[k] += 4.0 * (row[i][k] * w0 + row[i + 1][k] * w1);
                }
            }
            avg
        })
        .collect()
}

/// src/render/ggx_albedo.rs for `table` (its averages computed from it).
pub fn ggx_albedo_table_source(table: &[[f64; 2]]) -> String {
    let mut s = String::from(
        "//! GENERATED by tests/render_ggx.rs (albedo_table_is_the_quadrature; VKVCM_WRITE_GGX_TABLE=1\n\
         //! rewrites it) from tests/common/ggx.rs: the directional albedo E = f0 A + B of the GGX\n\
         //! lobe with Schlick's F of F0 f0 (glsl/bsdf.glsl, ggx_albedo), as (A, B) pairs by cosine\n\
         //! (i / (MU - 1))^2 and roughness j / (R - 1) (width max(r^2, MIN_GGX_ALPHA)), and\n\
         //! their cosine-weighted averages per roughness, exact for the kernels' bilinear\n\
         //! interpolation. The kernels read them from the scene's texel buffer\n\
         //! `ggx_albedo_table` (src/render/albedo_tables.rs).\n\n",
    );
    s += &format!("pub const GGX_ALBEDO_MU: usize = {N_MU};\npub const GGX_ALBEDO_R: usize = {N_R};\n\n");
    let array = |s: &mut String, name: &str, len: &str, values: &[[f64; 2]]| {
        *s += &format!("#[rustfmt::skip]\npub const {name}: [[f32; 2]; {len}] = [\n");
        let v: Vec<String> = values.iter().map(|[a, b]| format!("[{a:.5}, {b:.5}]")).collect();
        for c in v.chunks(6) {
            *s += &format!("    {},\n", c.join(", "));
        }
        *s += "];\n";
    };
    array(&mut s, "GGX_ALBEDO", "GGX_ALBEDO_MU * GGX_ALBEDO_R", table);
    s += "\n";
    array(&mut s, "GGX_ALBEDO_AVERAGE", "GGX_ALBEDO_R", &ggx_albedo_averages(table));

    s
}

/// The tables src/render/ggx_albedo.rs holds: (A, B) pairs, and their averages.
pub fn committed_ggx_albedo_table() -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    use vkvcm::render::ggx_albedo::{GGX_ALBEDO, GGX_ALBEDO_AVERAGE};
    let wide = |t: &[[f32; 2]]| t.iter().map(|p| [p[0] as f64, p[1] as f64]).collect();
    (wide(&GGX_ALBEDO), wide(&GGX_ALBEDO_AVERAGE))
}

/// (A, B) at (mu, alpha) by the table's bilinear interpolation, as glsl/bsdf.glsl's
/// ggx_albedo_terms.
pub fn table_lookup(table: &[[f64; 2]], mu: f64, alpha: f64) -> [f64; 2] {
    let x = mu.clamp(0.0, 1.0).sqrt() * (N_MU - 1) as f64;
    let y = alpha.clamp(0.0, 1.0).sqrt() * (N_R - 1) as f64;
    let (i, j) = ((x as usize).min(N_MU - 2), (y as usize).min(N_R - 2));
    let (fx, fy) = (x - i as f64, y - j as f64);
    let at = |i: usize, j: usize, k: usize| table[j * N_MU + i][k];
    std::array::from_fn(|k| {
        let lo = at(i, j, k) + (at(i + 1, j, k) - at(i, j, k)) * fx;
        let hi = at(i, j + 1, k) + (at(i + 1, j + 1, k) - at(i, j + 1, k)) * fx;
        lo + (hi - lo) * fy
    })
}

/// The averages' linear interpolation at `alpha`, as glsl/bsdf.glsl's ggx_albedo_average.
pub fn average_lookup(averages: &[[f64; 2]], alpha: f64) -> [f64; 2] {
    let y = alpha.clamp(0.0, 1.0).sqrt() * (N_R - 1) as f64;
    let j = (y as usize).min(N_R - 2);
    let fy = y - j as f64;
    std::array::from_fn(|k| averages[j][k] + (averages[j + 1][k] - averages[j][k]) * fy)
}

/// The committed tables as the kernels use them.
pub struct GgxAlbedo {
    table: Vec<[f64; 2]>,
    averages: Vec<[f64; 2]>,
}

impl GgxAlbedo {
    pub fn committed() -> Self {
        let (table, averages) = committed_ggx_albedo_table();
        GgxAlbedo { table, averages }
    }

    /// E(mu) of the lobe with Schlick's F of F0 `f0`, width `alpha`.
    pub fn albedo(&self, f0: f64, mu: f64, alpha: f64) -> f64 {
        let [a, b] = table_lookup(&self.table, mu, alpha);
        f0 * a + b
    }

    /// E_avg = 2 int_0^1 E(mu) mu dmu.
    pub fn average(&self, f0: f64, alpha: f64) -> f64 {
        let [a, b] = average_lookup(&self.averages, alpha);
        f0 * a + b
    }
}
