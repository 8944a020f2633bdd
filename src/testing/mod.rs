//! Checks a unit from another crate can run on itself as hppm's own are run: for a BSDF, its
//! WGSL against its CPU model, its sampler against its pdf and its energy ([`bsdf`]). They
//! measure; a test states what it holds the figures to.

pub mod bsdf;
