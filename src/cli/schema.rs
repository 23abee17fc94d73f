//! `grainline schema`: the scene file's JSON Schema.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

/// Arguments of `grainline schema`.
#[derive(Debug, Args)]
pub struct SchemaArgs {
    /// Write the schema here instead of standard output.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

/// Runs `grainline schema`.
pub fn run(args: SchemaArgs) -> anyhow::Result<()> {
    let text = grainline::scene::json_schema_text();
    match args.out {
        Some(p) => grainline::output::OutputPlan::new()
            .output("--out", &p)
            .check()
            .and_then(|_| grainline::output::write_atomic(&p, text.as_bytes()))
            .with_context(|| format!("writing {}", p.display()))?,
        None => print!("{text}"),
    }
    Ok(())
}
