// Ray/primitive tests. Mirrored exactly by src/bvh/intersect.rs (same operations, same
// order); the intermediate values are `precise` so the compiler neither fuses them into
// FMAs nor reorders them, which the watertightness argument below depends on.
//
// Triangles: watertight test of Woop, Benthin & Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2(1), 2013. The ray is mapped to +z by an axis permutation and a
// shear computed once per ray (ray_shear); the edge functions of an edge shared by two
// triangles are then computed from the same sheared vertex coordinates and are exact
// negations of each other, so a ray through a shared edge or vertex of a closed mesh
// cannot pass between its triangles. (An edge function that is exactly 0 is accepted by
// both neighbours; the paper's double-precision re-test is not needed for watertightness
// and is not done.)
//
// Spheres: Haines, Guenther & Akenine-Moeller, "Precision Improvements for Ray/Sphere
// Intersection", Ray Tracing Gems ch. 7, 2019: the discriminant comes from the distance
// between the centre and the ray's closest approach, the roots from c/q and q/a.
//
// Directions need not be normalised; t is in units of the direction's length.
#ifndef VKVCM_INTERSECT_GLSL
#define VKVCM_INTERSECT_GLSL

struct RayShear {
    int kx;
    int ky;
    int kz;
    float sx;
    float sy;
    float sz;
};

RayShear ray_shear(vec3 d) {
    vec3 a = abs(d);
    int kz = (a.x >= a.y && a.x >= a.z) ? 0 : ((a.y >= a.z) ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0) {
        int tmp = kx;
        kx = ky;
        ky = tmp;
    }
    RayShear s;
    s.kx = kx;
    s.ky = ky;
    s.kz = kz;
    s.sx = d[kx] / d[kz];
    s.sy = d[ky] / d[kz];
    s.sz = 1.0 / d[kz];
    return s;
}

// Watertight ray/triangle test; on a hit with tmin <= t <= tmax returns true and the
// barycentric weights u (of v1) and v (of v2).
bool intersect_triangle(vec3 o, RayShear sh, vec3 v0, vec3 v1, vec3 v2, float tmin,
                        float tmax, out float t, out float u, out float v) {
    precise vec3 a = v0 - o;
    precise vec3 b = v1 - o;
    precise vec3 c = v2 - o;
    precise float ax = a[sh.kx] - sh.sx * a[sh.kz];
    precise float ay = a[sh.ky] - sh.sy * a[sh.kz];
    precise float bx = b[sh.kx] - sh.sx * b[sh.kz];
    precise float by = b[sh.ky] - sh.sy * b[sh.kz];
    precise float cx = c[sh.kx] - sh.sx * c[sh.kz];
    precise float cy = c[sh.ky] - sh.sy * c[sh.kz];
    precise float eu = cx * by - cy * bx;
    precise float ev = ax * cy - ay * cx;
    precise float ew = bx * ay - by * ax;
    t = 0.0;
    u = 0.0;
    v = 0.0;
    if ((eu < 0.0 || ev < 0.0 || ew < 0.0) && (eu > 0.0 || ev > 0.0 || ew > 0.0)) {
        return false;
    }
    precise float det = eu + ev + ew;
    if (det == 0.0) {
        return false;
    }
    precise float az = sh.sz * a[sh.kz];
    precise float bz = sh.sz * b[sh.kz];
    precise float cz = sh.sz * c[sh.kz];
    precise float tt = eu * az + ev * bz + ew * cz;
    // Compare t = tt / det with [tmin, tmax] without dividing (sign of det folded in).
    float ts = det < 0.0 ? -tt : tt;
    float ds = abs(det);
    if (!(ts >= tmin * ds && ts <= tmax * ds)) {
        return false;
    }
    float rcp = 1.0 / det;
    t = tt * rcp;
    u = ev * rcp;
    v = ew * rcp;
    return true;
}

// Ray/sphere test (Ray Tracing Gems ch. 7): the smaller root in [tmin, tmax], else the
// larger one in it.
bool intersect_sphere(vec3 o, vec3 d, vec3 center, float radius, float tmin, float tmax,
                      out float t) {
    vec3 f = o - center;
    float a = dot(d, d);
    float bp = -dot(f, d);
    vec3 l = f + (bp / a) * d;
    float r2 = radius * radius;
    float disc = a * (r2 - dot(l, l));
    t = 0.0;
    if (!(disc >= 0.0)) {
        return false;
    }
    float c = dot(f, f) - r2;
    float sq = sqrt(disc);
    float q = bp + (bp >= 0.0 ? sq : -sq);
    float t0 = c / q;
    float t1 = q / a;
    float tn = min(t0, t1);
    float tf = max(t0, t1);
    if (tn >= tmin && tn <= tmax) {
        t = tn;
        return true;
    }
    if (tf >= tmin && tf <= tmax) {
        t = tf;
        return true;
    }
    return false;
}

#endif
