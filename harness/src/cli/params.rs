//! `nc-conform params --from-ini MACHINE.ini [--out FILE.yaml]`: a LinuxCNC machine's INI file as
//! `linuxcnc` dialect parameters ([`crate::ini`]).

use std::path::PathBuf;

use clap::Args;

use super::{display_name, EXIT_INPUT, EXIT_OK};
use crate::diag::InputError;
use crate::{ini, input};

/// Arguments of `params`.
#[derive(Debug, Args)]
pub struct ParamsArgs {
    /// The LinuxCNC INI file whose [AXIS_*]/[JOINT_*] MAX_VELOCITY and MAX_ACCELERATION, [TRAJ],
    /// [EMCMOT], [SPINDLE_0] and [DISPLAY] values become the linuxcnc parameters.
    #[arg(long, value_name = "MACHINE.ini")]
    pub from_ini: PathBuf,
    /// Write the parameter file here instead of standard output.
    #[arg(long, value_name = "FILE.yaml")]
    pub out: Option<PathBuf>,
}

/// Carries out `nc-conform params`; returns the exit status (0, or 2 for an input error).
pub fn run(args: &ParamsArgs) -> u8 {
    let inner = || -> Result<(), InputError> {
        let name = display_name(&args.from_ini);
        let text = input::read_text(&args.from_ini, input::YAML)?;
        let parsed = ini::Ini::parse(&text).map_err(|e| {
            let mut err = InputError::new(format!("{name}:{}", e.line), e.message);
            err.expected = Some("[SECTION] headers and KEY = value lines".into());
            err
        })?;
        let file = ini::params_file(&ini::map(&parsed), &name);
        super::write_or_print(args.out.as_deref(), &file)
    };
    match inner() {
        Ok(()) => EXIT_OK,
        Err(e) => {
            e.report();
            EXIT_INPUT
        }
    }
}
