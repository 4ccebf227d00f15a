//! Dual consensus ADMM (Algorithm 2) and its inexact variant.

pub mod agent;
