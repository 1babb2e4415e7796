// The film: per pixel a running sum of sample values in float32 with Kahan compensation
// (Kahan 1965), so that long renders lose no precision, without requiring float64.
// Each pixel has one writer per dispatch, so the result is deterministic.
// Requires `film[]` (vec4, two entries per pixel: sum, compensation) and `stats[]`
// (uint: [0] rejected samples) declared by the kernel.
#ifndef FILM_GLSL
#define FILM_GLSL

// Adds `v`; rejects (and counts) NaN, Inf and negative values instead of adding them.
void film_add(uint pixel, vec3 v) {
    if (!finite3(v) || any(lessThan(v, vec3(0.0)))) {
        atomicAdd(stats[0], 1u);
        return;
    }
    vec4 sum = film[2u * pixel];
    vec4 c = film[2u * pixel + 1u];
    vec4 y = vec4(v, 0.0) - c;
    vec4 t = sum + y;
    film[2u * pixel + 1u] = (t - sum) - y;
    film[2u * pixel] = t;
}

#endif
