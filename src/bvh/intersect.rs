//! Ray/primitive tests shared by the CPU traversal and the brute-force reference. They
//! perform the same float operations, in the same order, as glsl/intersect.glsl (which
//! marks them `precise` so that the compiler neither contracts nor reorders them).
//!
//! * Triangles: watertight test of Woop, Benthin & Wald, "Watertight Ray/Triangle
//!   Intersection", JCGT 2(1), 2013. A ray through a shared edge or vertex of a closed
//!   mesh hits at least one of the adjacent triangles: the edge functions of a shared edge
//!   are computed from the same sheared vertex coordinates in both triangles and are exact
//!   negations of each other. (The paper's double-precision re-evaluation of zero edge
//!   functions is not used: an exactly-zero edge function is accepted by both neighbours,
//!   so the test stays watertight and reports either triangle.)
//! * Spheres: Haines, Günther & Akenine-Möller, "Precision Improvements for Ray/Sphere
//!   Intersection", Ray Tracing Gems ch. 7, 2019: the discriminant is formed from the
//!   distance between the centre and the ray's closest approach, and the two roots as
//!   `c/q` and `q/a` to avoid cancellation.
//!
//! Directions need not be normalised; `t` is in units of the direction's length.

use glam::Vec3;

use crate::scene::{Sphere, Triangle};

/// A ray `o + t d`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
}

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Original index in `Scene::triangles`, or in `Scene::spheres` when `is_sphere`.
    pub prim: u32,
    /// Barycentric weights of v1 and v2 (the hit point is `(1-u-v) v0 + u v1 + v v2`);
    /// 0 for spheres.
    pub u: f32,
    pub v: f32,
    pub is_sphere: bool,
    pub material: u32,
    /// The instance (index in `Scene::instances`) whose mesh the triangle belongs to;
    /// `None` for world-space primitives.
    pub instance: Option<u32>,
}

/// Per-ray set-up of the watertight triangle test: the axis permutation and shear that
/// map the ray direction to +z.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub k: [usize; 3],
    pub s: [f32; 3],
}

impl RayShear {
    pub fn new(d: Vec3) -> RayShear {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = if kz == 2 { 0 } else { kz + 1 };
        let mut ky = if kx == 2 { 0 } else { kx + 1 };
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        RayShear { k: [kx, ky, kz], s: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]] }
    }
}

/// Watertight ray/triangle test. Returns `(t, u, v)` for a hit with `tmin <= t <= tmax`
/// (`u`, `v`: barycentric weights of `v1`, `v2`).
#[inline]
#[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must fail the test
pub fn intersect_triangle(o: Vec3, sh: &RayShear, p: &[Vec3; 3], tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
    let [kx, ky, kz] = sh.k;
    let [sx, sy, sz] = sh.s;
    let a = p[0] - o;
    let b = p[1] - o;
    let c = p[2] - o;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let az = sz * a[kz];
    let bz = sz * b[kz];
    let cz = sz * c[kz];
    let tt = u * az + v * bz + w * cz;
    // Compare t = tt / det with the interval without dividing (sign of det folded in).
    let (ts, ds) = if det < 0.0 { (-tt, -det) } else { (tt, det) };
    if !(ts >= tmin * ds && ts <= tmax * ds) {
        return None;
    }
    let rcp = 1.0 / det;
    Some((tt * rcp, v * rcp, w * rcp))
}

/// Ray/sphere test (Ray Tracing Gems ch. 7). Returns the smaller root in `[tmin, tmax]`,
/// else the larger one in it.
#[inline]
#[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must fail the test
pub fn intersect_sphere(o: Vec3, d: Vec3, center: Vec3, radius: f32, tmin: f32, tmax: f32) -> Option<f32> {
    let f = o - center;
    let a = d.dot(d);
    let bp = -f.dot(d);
    let l = f + (bp / a) * d;
    let r2 = radius * radius;
    let disc = a * (r2 - l.dot(l));
    if !(disc >= 0.0) {
        return None;
    }
    let c = f.dot(f) - r2;
    let q = bp + if bp >= 0.0 { disc.sqrt() } else { -disc.sqrt() };
    let t0 = c / q;
    let t1 = q / a;
    let (tn, tf) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    if tn >= tmin && tn <= tmax {
        Some(tn)
    } else if tf >= tmin && tf <= tmax {
        Some(tf)
    } else {
        None
    }
}

pub(crate) fn triangle_is_finite(t: &Triangle) -> bool {
    t.p.iter().all(|p| p.is_finite())
}

pub(crate) fn sphere_is_finite(s: &Sphere) -> bool {
    s.center.is_finite() && s.radius.is_finite()
}

/// Closest hit in `[tmin, tmax]` by testing every primitive (the reference for tests).
/// Primitives with non-finite coordinates are skipped, as the builder does.
pub fn brute_force_closest(
    triangles: &[Triangle],
    spheres: &[Sphere],
    ray: &Ray,
    tmin: f32,
    mut tmax: f32,
) -> Option<Hit> {
    let sh = RayShear::new(ray.d);
    let mut best = None;
    for (i, tri) in triangles.iter().enumerate() {
        if !triangle_is_finite(tri) {
            continue;
        }
        if let Some((t, u, v)) = intersect_triangle(ray.o, &sh, &tri.p, tmin, tmax) {
            tmax = t;
            best = Some(Hit { t, prim: i as u32, u, v, is_sphere: false, material: tri.material, instance: None });
        }
    }
    for (i, s) in spheres.iter().enumerate() {
        if !sphere_is_finite(s) {
            continue;
        }
        if let Some(t) = intersect_sphere(ray.o, ray.d, s.center, s.radius.abs(), tmin, tmax) {
            tmax = t;
            best =
                Some(Hit { t, prim: i as u32, u: 0.0, v: 0.0, is_sphere: true, material: s.material, instance: None });
        }
    }
    best
}

/// Whether any primitive is hit in `[tmin, tmax]`, by testing every primitive.
pub fn brute_force_any(triangles: &[Triangle], spheres: &[Sphere], ray: &Ray, tmin: f32, tmax: f32) -> bool {
    let sh = RayShear::new(ray.d);
    triangles.iter().any(|tri| triangle_is_finite(tri) && intersect_triangle(ray.o, &sh, &tri.p, tmin, tmax).is_some())
        || spheres.iter().any(|s| {
            sphere_is_finite(s) && intersect_sphere(ray.o, ray.d, s.center, s.radius.abs(), tmin, tmax).is_some()
        })
}
