//! Axis-aligned boxes: the bounds the builder works with and the GPU layout quantises.

use glam::Vec3;

/// Axis-aligned box. The empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    pub fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }

    pub fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        let mut b = *self;
        b.grow(o);
        b
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.cmple(self.max).all())
    }

    /// Half the surface area (0 for an empty box), in f64 so that huge boxes do not
    /// overflow.
    pub fn half_area(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let e = (self.max - self.min).as_dvec3();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    pub fn contains(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && o.max.cmple(self.max).all()
    }

    /// The box grown by `|x| * 2^-20 + 1e-20` on each side: what the GPU nodes store.
    /// The padding makes the slab test conservative for a ray that starts exactly on a
    /// box plane and runs parallel to it (its clamped `1/d = 1e30` then meets a nonzero
    /// distance to the plane), and absorbs the rounding of the box coordinates.
    pub fn padded(&self) -> Aabb {
        let pad = |x: Vec3| x.abs() * (1.0 / 1_048_576.0) + Vec3::splat(1e-20);
        Aabb { min: self.min - pad(self.min), max: self.max + pad(self.max) }
    }

    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
}
