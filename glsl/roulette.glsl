// Russian roulette of camera paths (pt, and the camera subpaths of bpt and vcm), Cycles'
// rule (path_state_continuation_probability): none at the first RR_MIN_LENGTH - 1
// vertices, then the path continues with probability min(1, sqrt(maxcomp(throughput *
// eta_scale))), eta_scale undoing the eta^2 radiance scaling of refraction. The square
// root ends fewer paths than pbrt-v4's p = maxcomp(...), which kills many whose next
// segment would still find the sky. Light subpaths keep SmallVCM's per-vertex albedo rule
// (bsdf.glsl's cont_prob): their throughput is in units of power, not a fraction.
#ifndef ROULETTE_GLSL
#define ROULETTE_GLSL

// Roulette applies at vertices whose path so far has at least this many segments (the
// camera's first hit has 1): a later start lowers the variance per sample but costs more
// than it saves in closed rooms (docs/performance.md, "Defaults that matter for speed,
// and why").
const uint RR_MIN_LENGTH = 3u;

// `eta_scale` after the BSDF sample `wi` at `b`: refraction scales radiance by eta_ratio^2
// (bsdf.glsl), which the roulette undoes.
float roulette_eta_scale(float eta_scale, Bsdf b, vec3 wi) {
    return dot(wi, b.ng) * dot(b.wo, b.ng) < 0.0 ? eta_scale / (b.eta_ratio * b.eta_ratio) : eta_scale;
}

// The probability that a camera path with `len` segments and throughput `thr` (after the
// vertex's BSDF sample) continues.
float roulette_continuation(vec3 thr, float eta_scale, uint len) {
    return len >= RR_MIN_LENGTH ? min(1.0, sqrt(max3(thr) * eta_scale)) : 1.0;
}

#endif
