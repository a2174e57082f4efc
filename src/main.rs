//! `antiradiance` command-line tool: parses arguments into options and calls the library.

mod cli;

use anyhow::Result;
use clap::Parser;
use cli::args::{Cli, Command};

/// Errors are one line (`Error: ...`, causes joined with `: `), whatever RUST_BACKTRACE says.
/// Keeps freed heap memory mapped for this process (glibc's trim and mmap thresholds).
/// lavapipe frees and reallocates its binned scene (64 KB blocks, tens of MB per global pass)
/// at every render pass; with glibc's default trim threshold the freed top of the heap goes back
/// to the kernel and is faulted in and zeroed again the next pass. Setting a threshold turns
/// glibc's adaptive mmap threshold off, so it is fixed at its largest (32 MB): otherwise every
/// buffer above 128 KB (shadow atlases, tables read back) would be a fresh mmap. Measured: the
/// Cornell box's system time per `profile` run 1.2 → 0.6 s, 4–7% off the iteration; Veach's
/// light setup unchanged (1.4 s with the trim threshold alone). The driver's choice, not the
/// library's: an embedding host keeps its own allocator settings.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes the allocator's parameters; called before any other thread.
    unsafe {
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
    }
}

fn main() -> std::process::ExitCode {
    keep_freed_memory();
    // Output piped into `head` and the like ends quietly, as other command-line tools do,
    // instead of a panic in println! on the closed pipe.
    #[cfg(unix)]
    // SAFETY: restores the default disposition of one signal before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => e.exit(), // --help, --version
        Err(e) => {
            // clap's first line names the flag and the value; usage hints are dropped.
            let text = e.to_string();
            let line = text.lines().next().unwrap_or("invalid arguments");
            eprintln!("Error: {}", line.trim_start_matches("error: "));
            return std::process::ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("Error: {}", format!("{e:#}").replace('\n', " "));
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Animate(a) => a.run(),
        Command::Compare(a) => a.run(),
        Command::Info(a) => a.run(),
        Command::Profile(a) => a.run(),
        Command::Reference(a) => a.run(),
        Command::Render(a) => a.run(),
        Command::Study(a) => a.run(),
        Command::View(a) => a.run(),
    }
}
