//! The `nc-conform` command: see [`nc_conform::cli`].

fn main() -> std::process::ExitCode {
    nc_conform::cli::main()
}
