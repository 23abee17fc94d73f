//! `grainline edit`: the interactive editor on a local page (src/editor).

use std::io::Write;
use std::path::PathBuf;

use clap::Args;
use grainline::editor::{Editor, EditorOptions};

/// Arguments of `grainline edit`.
#[derive(Debug, Args)]
pub struct EditArgs {
    /// The scene file (docs/scene.md); Save writes the edits back into it.
    scene: PathBuf,
    /// The port on 127.0.0.1 (0 picks a free one).
    #[arg(long, value_name = "N", default_value_t = 8470)]
    port: u16,
    /// Open the page in the default browser.
    #[arg(long)]
    open: bool,
}

/// Runs `grainline edit`: the page's URL is the first line on standard output.
pub fn run(args: EditArgs, quiet: bool) -> anyhow::Result<()> {
    let editor = Editor::bind(&args.scene, &EditorOptions { port: args.port })?;
    let url = editor.url();
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{url}")?;
        out.flush()?;
    }
    if !quiet {
        eprintln!(
            "grainline edit: {} on {url} (Ctrl-C ends it; Save writes {})",
            args.scene.display(),
            args.scene.display()
        );
    }
    if args.open {
        open_browser(&url);
    }
    editor.run()?;
    Ok(())
}

/// Asks the desktop to open `url`; a failure is only a note (the URL is printed).
fn open_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") { "open" } else { "xdg-open" };
    if let Err(e) = std::process::Command::new(opener)
        .arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
    {
        eprintln!("grainline edit: note: could not run {opener}: {e}; open {url} by hand");
    }
}
