//! The probability with which next-event estimation and light subpaths choose each light,
//! and the table the kernels draw it from (glsl/lights.glsl, `pick_light`,
//! `light_pick_prob`). Every estimator's MIS weights use the same probabilities, so any
//! choice is unbiased; what it changes is variance.
//!
//! [`LightSelection::Power`] picks a light in proportion to its emitted power, as pbrt-v4's
//! `PowerLightSampler` does (Pharr, Jakob, Humphreys, "Physically Based Rendering", 4th
//! ed., 12.6.2), with pbrt-v4's power of each kind (its `Phi`): an area light pi A L, a
//! point light 4 pi I, a spot light 2 pi I (1 - (cos_inner + cos_outer) / 2), and lights
//! at infinity as if they shone on a disc of the scene's bounding radius r: a sun
//! pi r^2 E, a background 4 pi pi r^2 times its mean radiance over the sphere. Colours
//! count by their luminance. [`LightSelection::Uniform`] is SmallVCM's 1 / #lights.
//!
//! The table is Walker's alias method with Vose's construction (M. D. Vose, "A linear
//! algorithm for generating random numbers with a given distribution", IEEE TSE 1991): one
//! uniform number u picks slot i = floor(u n) and, with the fraction u n - i, keeps i if it
//! is below the slot's threshold, else takes the slot's alias. The probability the kernels
//! divide by is computed back from the table itself (`prob`), so it is exactly the
//! frequency the table draws with, up to f32 rounding. Lights of equal power (to a
//! relative 1e-6) get the uniform table, so such scenes render exactly as with uniform
//! selection.

use glam::Vec3;

use super::settings::LightSelection;
use crate::scene::environment::luminance;
use crate::scene::{Light, Scene, Triangle};

/// The selection table of a scene's lights, indexed like `Scene::lights`.
#[derive(Clone, Debug, PartialEq)]
pub struct LightDistribution {
    /// The probability of picking each light.
    pub prob: Vec<f32>,
    /// Per slot: the fraction of the slot's 1 / n that stays with its own light.
    pub threshold: Vec<f32>,
    /// Per slot: the light that takes the rest of the slot.
    pub alias: Vec<u32>,
}

impl LightDistribution {
    /// The table for `scene`'s lights under `selection`.
    pub fn new(scene: &Scene, selection: LightSelection) -> LightDistribution {
        match selection {
            LightSelection::Uniform => LightDistribution::uniform(scene.lights.len()),
            // The tree's light subpaths start by power (src/render/light_tree.rs).
            LightSelection::Power | LightSelection::Tree => {
                let (_, radius) = scene.bounding_sphere();
                let power: Vec<f64> = scene.lights.iter().map(|l| light_power(l, &scene.triangles, radius)).collect();
                LightDistribution::from_weights(&power)
            }
        }
    }

    /// Every one of `n` lights with probability 1 / n: each slot keeps its own light, so
    /// the kernels draw exactly as with min(floor(u n), n - 1).
    pub fn uniform(n: usize) -> LightDistribution {
        LightDistribution { prob: vec![1.0 / n as f32; n], threshold: vec![1.0; n], alias: (0..n as u32).collect() }
    }

    /// The table for probabilities proportional to `weights` (non-negative; a weight that
    /// is not finite or not positive gets probability 0). All zero: uniform.
    pub fn from_weights(weights: &[f64]) -> LightDistribution {
        let n = weights.len();
        let w: Vec<f64> = weights.iter().map(|&x| if x.is_finite() && x > 0.0 { x } else { 0.0 }).collect();
        let total: f64 = w.iter().sum();
        if n == 0 || total <= 0.0 || !total.is_finite() {
            return LightDistribution::uniform(n);
        }
        // Equal weights (to rounding: the two triangles of a quad light rarely have
        // bit-equal areas) are the uniform table exactly.
        let (lo, hi) = w.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        if lo > 0.0 && hi - lo <= 1e-6 * hi {
            return LightDistribution::uniform(n);
        }
        // Vose: scaled probabilities n p_i; slots below 1 are topped up from slots above.
        let mut scaled: Vec<f64> = w.iter().map(|x| x / total * n as f64).collect();
        let mut threshold = vec![1.0f64; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            threshold[s] = scaled[s];
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left (rounding) keeps its own slot whole.
        for i in small.into_iter().chain(large) {
            threshold[i] = 1.0;
            alias[i] = i as u32;
        }
        let threshold: Vec<f32> = threshold.iter().map(|&t| t as f32).collect();
        // The probability the table draws each light with: its slots' kept fractions and
        // the other slots' remainders that alias to it.
        let mut mass = vec![0.0f64; n];
        for i in 0..n {
            let t = threshold[i] as f64;
            mass[i] += t;
            mass[alias[i] as usize] += 1.0 - t;
        }
        let prob = mass.iter().map(|m| (m / n as f64) as f32).collect();
        LightDistribution { prob, threshold, alias }
    }
}

/// The power of `light` for [`LightSelection::Power`] (the module's header), in the
/// luminance of its colour; `triangles`: the scene's (area lights name theirs), `radius`:
/// its bounding radius.
pub fn light_power(light: &Light, triangles: &[Triangle], radius: f32) -> f64 {
    use std::f64::consts::PI;
    let lum = |c: Vec3| luminance(c.to_array()) as f64;
    let disc = PI * (radius as f64).powi(2);
    match light {
        Light::Area { triangle, radiance } => {
            let area = triangles
                .get(*triangle as usize)
                .map_or(0.0, |t| 0.5 * (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).length() as f64);
            PI * area * lum(*radiance)
        }
        Light::Point { intensity, .. } => 4.0 * PI * lum(*intensity),
        Light::Spot { intensity, cos_inner, cos_outer, .. } => {
            2.0 * PI * (1.0 - 0.5 * (*cos_inner as f64 + *cos_outer as f64)) * lum(*intensity)
        }
        Light::Directional { irradiance, .. } => disc * lum(*irradiance),
        Light::Background { radiance } => 4.0 * PI * disc * lum(*radiance),
        Light::Environment(e) => {
            // The mean radiance over the sphere: texel rows weighted by sin(theta).
            let (w, h) = (e.map.width, e.map.height);
            let (mut sum, mut weight) = (0.0f64, 0.0f64);
            for y in 0..h {
                let s = ((y as f64 + 0.5) / h as f64 * PI).sin();
                for x in 0..w {
                    sum += s * lum(Vec3::from_array(e.map.texel(x, y)) * e.scale);
                    weight += s;
                }
            }
            4.0 * PI * disc * if weight > 0.0 { sum / weight } else { 0.0 }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frequency with which the kernels' draw (glsl/lights.glsl, `pick_light`) picks
    /// each light, integrated exactly over u: slot i covers [i / n, (i + 1) / n), its first
    /// threshold / n keeps light i, the rest goes to its alias.
    fn drawn(d: &LightDistribution) -> Vec<f64> {
        let n = d.prob.len();
        let mut f = vec![0.0; n];
        for i in 0..n {
            let t = d.threshold[i] as f64;
            f[i] += t / n as f64;
            f[d.alias[i] as usize] += (1.0 - t) / n as f64;
        }
        f
    }

    #[test]
    fn the_table_draws_in_proportion_to_the_weights() {
        let weights = [1.0, 0.0, 5.0, 0.25, 3.75, 10.0, f64::NAN, 0.5];
        let d = LightDistribution::from_weights(&weights);
        let total: f64 = 20.5;
        for (i, (&p, f)) in d.prob.iter().zip(drawn(&d)).enumerate() {
            let want = if weights[i].is_finite() { weights[i] / total } else { 0.0 };
            assert!((p as f64 - want).abs() < 1e-6, "light {i}: prob {p}, want {want}");
            assert!((f - p as f64).abs() < 1e-7, "light {i}: drawn {f}, prob {p}");
        }
        assert!(d.threshold.iter().all(|&t| (0.0..=1.0).contains(&t)));
        // A light of weight 0 is never drawn: no slot keeps it or aliases to it.
        assert_eq!(drawn(&d)[1], 0.0);
        assert!(d.alias.iter().enumerate().all(|(i, &a)| a != 1 || (i != 1 && d.threshold[i] == 1.0)));
    }

    /// pbrt-v4's power of each kind (the module's header), in luminance.
    #[test]
    fn light_power_by_kind() {
        use std::f64::consts::PI;
        let triangles = [Triangle { p: [Vec3::ZERO, Vec3::X, Vec3::Y], n: None, material: 0, attributes: None }];
        let r = 2.0f32;
        let disc = PI * 4.0;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-5 * b;
        let power = |l: Light| light_power(&l, &triangles, r);
        assert!(close(power(Light::Area { triangle: 0, radiance: Vec3::splat(2.0) }), PI * 0.5 * 2.0));
        assert!(close(power(Light::Point { position: Vec3::ZERO, intensity: Vec3::ONE }), 4.0 * PI));
        let spot = Light::Spot {
            position: Vec3::ZERO,
            direction: Vec3::Z,
            intensity: Vec3::ONE,
            cos_inner: 0.9,
            cos_outer: 0.7,
        };
        assert!(close(power(spot), 2.0 * PI * 0.2));
        assert!(close(power(Light::Directional { direction: Vec3::Z, irradiance: Vec3::ONE }), disc));
        assert!(close(power(Light::Background { radiance: Vec3::ONE }), 4.0 * PI * disc));
        // Luminance weights: pure blue counts 0.0722.
        assert!(close(power(Light::Point { position: Vec3::ZERO, intensity: Vec3::Z }), 4.0 * PI * 0.0722));
    }

    #[test]
    fn uniform_keeps_every_slot() {
        let d = LightDistribution::uniform(3);
        assert_eq!(d.prob, vec![1.0 / 3.0; 3]);
        assert_eq!((d.threshold, d.alias), (vec![1.0; 3], vec![0, 1, 2]));
        // Equal weights (to rounding) give the uniform table, and no weight at all too.
        assert_eq!(LightDistribution::from_weights(&[2.0, 2.0, 2.0]), LightDistribution::uniform(3));
        assert_eq!(LightDistribution::from_weights(&[2.0, 2.0 + 1e-9, 2.0]), LightDistribution::uniform(3));
        assert_ne!(LightDistribution::from_weights(&[2.0, 2.1, 2.0]), LightDistribution::uniform(3));
        assert_eq!(LightDistribution::from_weights(&[0.0, 0.0]), LightDistribution::uniform(2));
    }
}
