//! Which modes to trust, and at which order: the indicators of each mode (MAC, MPC,
//! EMAC, CMI, contributions; [`indicators`]) and the scan across orders with its
//! automatic choice ([`stabilization`]). The modes themselves come from
//! [`crate::pipeline::modes`]. Over a fleet of records, [`track`] follows each mode
//! from record to record, and [`compare`] puts two FRF sets and their models side by
//! side.

pub(crate) mod change;
pub mod compare;
pub mod indicators;
pub mod stabilization;
pub mod track;
