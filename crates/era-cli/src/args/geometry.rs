//! `--geometry FILE`: the test geometry of a run (identify, refine, oma, plot).

use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct GeometryArgs {
    /// Test geometry: UFF (datasets 15/2411 nodes, 82 trace lines, 18/2420 coordinate
    /// systems) or era's geometry CSV (node,x,y,z then from,to). Checked before the run;
    /// its nodes and lines are written into modes.uff ahead of the shapes, the report
    /// animates the modes on it and lists the channels that no node carries, and
    /// shapes/mode_NN.svg/png show each mode in three views (plot: with --model).
    #[arg(long, value_name = "FILE", help_heading = "Reading the file")]
    pub geometry: Option<PathBuf>,
}
