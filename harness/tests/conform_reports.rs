//! The conform suite's JUnit report (issue 14 §5): a `time` attribute per scenario and for the
//! suite, and a controller that fails by itself (timeout, crash, protocol) counted as an error,
//! not as a failure of the scenario's rules.

use std::path::PathBuf;

use nc_conform::conform::reference::Reference;
use nc_conform::conform::suite::{run_one, scenario_files, SuiteReport};
use nc_conform::conform::{Advanced, Controller, ControllerError, ErrorKind, Identity, Job, Loaded};
use nc_engine::input::{Condition, Input};
use nc_engine::trace::TraceEvent;
use nc_engine::units::Micros;

/// The reference, that breaks down on one dialect.
struct Flaky {
    inner: Reference,
    broken: bool,
}

impl Controller for Flaky {
    fn identity(&mut self) -> Result<Identity, ControllerError> {
        self.inner.identity()
    }
    fn load(&mut self, job: &Job) -> Result<Loaded, ControllerError> {
        self.broken = job.program.contains("G84");
        self.inner.load(job)
    }
    fn input(&mut self, t_us: Micros, input: &Input) -> Result<(), ControllerError> {
        self.inner.input(t_us, input)
    }
    fn advance(&mut self, until_us: Micros, stop_on: &[Condition]) -> Result<Advanced, ControllerError> {
        if self.broken {
            return Err(ControllerError::new(ErrorKind::Timeout, "no answer within 10000 ms"));
        }
        self.inner.advance(until_us, stop_on)
    }
    fn read(&mut self) -> Result<Vec<TraceEvent>, ControllerError> {
        self.inner.read()
    }
}

#[test]
fn junit_has_times_and_counts_controller_errors_as_errors() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut ctl = Flaky { inner: Reference::new(), broken: false };
    let id = ctl.identity().unwrap();
    let mut rep = SuiteReport::new(&id);
    for p in scenario_files(&root.join("scenarios/common/doc_examples")) {
        let name = p.strip_prefix(&root).unwrap().display().to_string();
        rep.scenarios.push(run_one(&mut ctl, &id.dialects, &p, &name).unwrap());
    }
    let errors = rep.scenarios.iter().filter(|v| v.errored()).count();
    assert!(errors > 0 && errors < rep.scenarios.len(), "some scenarios tap, some do not");
    let xml = rep.junit();
    assert!(xml.contains(&format!("errors=\"{errors}\"")), "{xml}");
    assert!(xml.contains("<error message="), "{xml}");
    let (_, failed, _) = rep.counts();
    assert!(xml.contains(&format!("failures=\"{}\"", failed - errors)), "{xml}");
    assert!(
        xml.matches("<testcase ").count() == xml.matches(" time=\"").count() - 2,
        "a time per case and suite:\n{xml}"
    );
}
