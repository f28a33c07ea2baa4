//! Drilling and conventional tapping cycles.
