// Russian roulette of camera paths (pt, and the camera subpaths of bpt and vcm), Cycles'
// rule (path_state_continuation_probability): none at the first vertices (RR_MIN_LENGTH,
// SUBPATH_RR_MIN_LENGTH), then the path continues with probability min(1,
// sqrt(maxcomp(throughput * eta_scale))), eta_scale undoing the eta^2 radiance scaling
// of refraction. The square root ends fewer paths than pbrt-v4's p = maxcomp(...), which
// kills many whose next segment would still find the sky. Light subpaths keep SmallVCM's
// per-vertex albedo rule (bsdf.glsl's cont_prob): their throughput is in units of power,
// not a fraction.
#ifndef ROULETTE_GLSL
#define ROULETTE_GLSL

// pt's roulette applies at vertices whose path so far has at least this many segments
// (the camera's first hit has 1): a later start lowers the variance per sample but costs
// more than it saves in closed rooms (docs/performance.md, "Defaults that matter for
// speed, and why").
const uint RR_MIN_LENGTH = 3u;
// The camera subpaths' roulette starts a vertex earlier: each of their vertices also
// connects to light vertices (and merges), so a longer path costs more than pt's
// (docs/performance.md, "The camera subpaths' roulette").
const uint SUBPATH_RR_MIN_LENGTH = 2u;

// `eta_scale` after the BSDF sample `wi` at `b`: refraction scales radiance by eta_ratio^2
// (bsdf.glsl), which the roulette undoes.
float roulette_eta_scale(float eta_scale, Bsdf b, vec3 wi) {
    return dot(wi, b.ng) * dot(b.wo, b.ng) < 0.0 ? eta_scale / (b.eta_ratio * b.eta_ratio) : eta_scale;
}

// The probability that a camera path with `len` segments and throughput `thr` (after the
// vertex's BSDF sample) continues, with the roulette from `min_len` segments on.
float roulette_continuation(vec3 thr, float eta_scale, uint len, uint min_len) {
    return len >= min_len ? min(1.0, sqrt(max3(thr) * eta_scale)) : 1.0;
}

#endif
