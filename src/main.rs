//! The `hppm` binary: the command line with the built-in passes.

fn main() -> std::process::ExitCode {
    hppm::cli::run(hppm::passes::Registry::builtin())
}
