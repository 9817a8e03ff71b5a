//! Batch evaluation over slices (SIMD kernels land here).
