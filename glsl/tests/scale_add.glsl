// Included by tests/roundtrip.comp: proves #include resolution from glsl/.
float scale_add(float a, float b) { return a * float(SCALE) + b; }
