//! `slope-estimator`: clouds in, slope estimates out.

use clap::Parser;
use slope_tools::cli::stop_on_signals;
use slope_tools::estimator::{run, EstimatorArgs};

fn main() -> anyhow::Result<()> {
    let args = EstimatorArgs::parse();
    args.common.init_logging();
    let stop = stop_on_signals()?;
    run(&args, &stop)?;
    Ok(())
}
