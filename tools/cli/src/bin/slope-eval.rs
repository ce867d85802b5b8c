//! `slope-eval`: the estimator run offline on recordings, against their
//! ground truth.

use clap::Parser;
use slope_tools::eval::{run, EvalArgs};

fn main() -> anyhow::Result<()> {
    let args = EvalArgs::parse();
    args.init_logging();
    let outcome = run(&args)?;
    outcome.check()
}
