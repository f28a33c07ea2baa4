//! The LinuxCNC adapter's parts that need no LinuxCNC (`examples/linuxcnc-adapter/test_adapter.py`):
//! the machine configuration it writes for a scenario reads back through `nc-conform params
//! --from-ini` as the scenario's parameters, what LinuxCNC cannot have is not applicable, a
//! recording becomes trace events (time 0, samples, blocks, functions, G33.1 phases, exact
//! decimals), and the stop conditions. The runs against LinuxCNC itself are
//! `scripts/linuxcnc-conform` (docs/linuxcnc-conformance.md).

use std::path::PathBuf;
use std::process::Command;

#[test]
fn the_linuxcnc_adapter_maps_parameters_recordings_and_conditions() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/linuxcnc-adapter");
    let out = Command::new("python3")
        .arg("test_adapter.py")
        .current_dir(&dir)
        .env("NC_CONFORM", env!("CARGO_BIN_EXE_nc-conform"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("python3 runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{text}");
    // Every test ran (none lost to an import error or a misnamed class).
    let ran: usize =
        text.split("Ran ").nth(1).and_then(|s| s.split(' ').next()).and_then(|n| n.parse().ok()).unwrap_or(0);
    assert!(ran >= 40, "{ran} tests ran:\n{text}");
}
