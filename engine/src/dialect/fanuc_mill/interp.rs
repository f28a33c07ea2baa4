//! TEMPORARY STUB (being replaced by the fanuc-mill interpreter).
use crate::alarm::{Alarm, AlarmKind};
use crate::dialect::Interpreter;
use crate::params::Params;
use crate::parse::Block;
use crate::plan::{Pos, Step};
pub struct FanucInterp;
impl FanucInterp {
    pub fn new(_: &Params) -> Self {
        FanucInterp
    }
}
impl Interpreter for FanucInterp {
    fn block(&mut self, _: &Block, _: &mut Vec<Step>) -> Result<(), Alarm> {
        Err(Alarm::new(AlarmKind::NotModelled, "stub"))
    }
    fn reset(&mut self, _: Pos) {}
    fn set_position(&mut self, _: Pos) {}
    fn modal(&self) -> Vec<String> {
        Vec::new()
    }
    fn rigid_mode(&self) -> bool {
        false
    }
}
