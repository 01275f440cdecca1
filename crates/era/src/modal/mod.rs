//! Which modes to trust, and at which order: the indicators of each mode (MAC, MPC,
//! EMAC, CMI, contributions; [`indicators`]) and the scan across orders with its
//! automatic choice ([`stabilization`]). The modes themselves come from
//! [`crate::pipeline::modes`].

pub mod indicators;
pub mod stabilization;
