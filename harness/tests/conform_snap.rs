//! DEC-122 reads a controller's sample within the tolerance of the reference's value at the same
//! time as the reference's. A controller standing where the reference moves within that tolerance
//! (it resumed a feed hold some milliseconds earlier) must still be read as standing: the
//! LinuxCNC adapter's `cycles/g81_feed_hold` held at Z -3.085 mm until its cycle start at 2119 ms,
//! the reference resumed at 2084 ms, and the hold was read as moving up to -3.0375 mm (DEC-155).

use nc_conform::check::Tolerances;
use nc_conform::conform::verdict::snap;
use nc_engine::trace::{AxisSpec, Event, Sample, Trace, TraceEvent, TraceMeta, AXES};

fn trace(z_nm: impl Fn(i64) -> i64) -> Trace {
    let axes = ['X', 'Y', 'Z']
        .iter()
        .enumerate()
        .map(|(index, &letter)| AxisSpec { letter, index, diameter: false, rotary: false })
        .collect();
    let meta = TraceMeta { dialect: "linuxcnc", axes, period_us: 1000, sample_us: 1000 };
    let events = (0..60)
        .map(|k| {
            let mut axes = [0; AXES];
            axes[2] = z_nm(k);
            TraceEvent {
                t_us: k as u64 * 1000,
                event: Event::Sample(Sample { axes, spindle_mrpm: 0, spindle_mdeg: 0 }),
            }
        })
        .collect();
    Trace { meta, events }
}

fn z(t: &Trace) -> Vec<i64> {
    t.events
        .iter()
        .filter_map(|e| match &e.event {
            Event::Sample(s) => Some(s.axes[2]),
            _ => None,
        })
        .collect()
}

#[test]
fn a_standing_controller_is_not_read_as_moving_with_the_reference() {
    // the reference holds at Z -3.06 mm until 20 ms, then feeds down at 1 µm/ms
    let reference = trace(|k| if k < 20 { -3_060_000 } else { -3_060_000 - (k - 20) * 1_000 });
    // the controller stands at -3.085 mm throughout (within 0.05 mm of both)
    let controller = trace(|_| -3_085_000);
    let tol = Tolerances { keypoint_mm: 0.05, ..Tolerances::default() };
    let read = z(&snap(&controller, &reference, &tol));
    assert!(read.iter().all(|&v| v == read[0]), "{read:?}");
    assert_eq!(read[0], -3_060_000, "read as the reference's where they agree");
    // a controller that moves is read sample by sample
    let moving = trace(|k| -3_060_000 - k * 1_000);
    let read = z(&snap(&moving, &reference, &tol));
    assert_eq!(read[30], -3_070_000, "the reference's value at 30 ms");
}
