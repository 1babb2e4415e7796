//! Image output (EXR, PNG) and error metrics.
