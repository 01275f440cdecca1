//! The command line's integration tests, one binary (one link) with a module per area;
//! `common` holds the helpers (the era binary, data files, the hostile-input watchdog).

mod auto_order;
mod batch_cli;
mod browser;
mod cli;
mod common;
mod experiment_cli;
mod formats_cli;
mod frf_cli;
mod friction_cli;
mod geometry_cli;
mod hostile_inputs;
mod hostile_outputs;
mod hostile_params;
mod messages_cli;
mod okid_cli;
mod oma_cli;
mod refine_cli;
mod report_cli;
mod report_layout;
mod shapes_cli;
mod signals;
mod track_cli;
mod trust;
