//! Bounding volume hierarchy: binned SAH build on the CPU, GPU node layout.
