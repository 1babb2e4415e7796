//! Estimators: each is a sequence of kernel dispatches per iteration.
