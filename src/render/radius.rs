//! The merge-radius schedule of progressive photon mapping as SmallVCM uses it
//! (Knaus & Zwicker 2011; docs/smallvcm.md 4.2): r_i = r_0 (i+1)^((alpha-1)/2) for the
//! 0-based iteration i, r_0 = radius factor x scene bounding-sphere radius, clamped to
//! at least 1e-7.

/// Defaults of SmallVCM: radius factor 0.003, alpha 0.75.
pub const DEFAULT_RADIUS_FACTOR: f32 = 0.003;
pub const DEFAULT_ALPHA: f32 = 0.75;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusSchedule {
    pub initial: f32,
    pub alpha: f32,
}

impl RadiusSchedule {
    pub fn new(radius_factor: f32, scene_radius: f32, alpha: f32) -> Self {
        RadiusSchedule { initial: radius_factor * scene_radius, alpha }
    }

    /// Radius of the 0-based iteration `i`.
    pub fn radius(&self, i: u64) -> f32 {
        let r = self.initial as f64 * ((i + 1) as f64).powf((self.alpha as f64 - 1.0) * 0.5);
        (r as f32).max(1e-7)
    }

    /// MIS factors (VM factor eta = pi r^2 N_L, VC factor 1/eta) for the given use of
    /// connections and merging (docs/smallvcm.md 4.4.1; eq. 20 of Georgiev 2012).
    pub fn mis_factors(&self, i: u64, light_paths: u32, use_vc: bool, use_vm: bool) -> (f32, f32) {
        let r = self.radius(i) as f64;
        let eta = std::f64::consts::PI * r * r * light_paths as f64;
        let vm = if use_vm { eta } else { 0.0 };
        let vc = if use_vc { 1.0 / eta } else { 0.0 };
        (vm as f32, vc as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_smallvcm_numbers() {
        // docs/smallvcm.md 4.2: r0 = 0.0066512 for scene radius 2.217060; 0.004988 at
        // i+1 = 10, 0.003740 at 100, 0.002805 at 1000.
        let s = RadiusSchedule::new(DEFAULT_RADIUS_FACTOR, 2.21706, DEFAULT_ALPHA);
        assert!((s.radius(0) - 0.0066512).abs() < 1e-7);
        assert!((s.radius(9) - 0.004988).abs() < 1e-6);
        assert!((s.radius(99) - 0.003740).abs() < 1e-6);
        assert!((s.radius(999) - 0.002805).abs() < 1e-6);
        assert_eq!(RadiusSchedule::new(1e-12, 1.0, 0.75).radius(0), 1e-7);
    }

    #[test]
    fn mis_factors_are_reciprocal() {
        let s = RadiusSchedule::new(0.01, 1.0, 0.75);
        let (vm, vc) = s.mis_factors(3, 4096, true, true);
        assert!((vm * vc - 1.0).abs() < 1e-5);
        assert_eq!(s.mis_factors(3, 4096, true, false).0, 0.0);
        assert_eq!(s.mis_factors(3, 4096, false, true).1, 0.0);
    }
}
