//! Alarms: every machine-level error the engine can raise, typed, with the vendor's number where
//! a source document gives one and a project number (`NC-xxxx`) where none does.
//!
//! The list of codes and texts is the contract with users' scripts: add, never renumber.

/// The kind of an alarm; its code and title are fixed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum AlarmKind {
    /// Fanuc 0010: a G code the dialect does not have.
    ImproperGCode,
    /// Fanuc 0011: feed rate zero (or not given) for a feed move or cycle.
    FeedZero,
    /// Fanuc 0200: S missing or out of range for rigid tapping.
    IllegalSCode,
    /// Fanuc 0201: no F in a rigid tapping cycle.
    FeedNotFoundRigid,
    /// Fanuc 0202: the spindle position distribution overflowed (lead × speed too high).
    PositionLsiOverflow,
    /// Fanuc 0203: M29 or S misplaced (M29 repeated, M29 without S, S changed in rigid mode).
    ProgramMissRigid,
    /// Fanuc 0204: an axis moved between M29 and the tapping cycle.
    IllegalAxisOperation,
    /// Fanuc 0205: RGTAP (G61.0) not on when the rigid tapping cycle runs.
    RigidModeDiOff,
    /// Fanuc 0206: the plane changed in rigid tapping mode.
    CannotChangePlane,
    /// Fanuc 0207: the tapping distance or data is inconsistent.
    RigidDataMismatch,
    /// Fanuc 0410: servo excess error at standstill.
    ExcessErrorStopped,
    /// Fanuc 0411: servo excess error while moving (tap and spindle out of sync).
    ExcessErrorMoving,
    /// PLC 5002: no position-mode answer after M29 within the PLC timer.
    M29FeedbackTimeout,
    /// PLC 5074: the spindle did not rotate during rigid tapping for longer than the timer.
    SpindleNotRotating,
    /// NC-1001: a word's value is outside its range.
    WordOutOfRange,
    /// NC-1002: a word the command needs is missing.
    WordMissing,
    /// NC-1003: a G code this dialect does not have (dialects without a vendor number).
    UnsupportedGCode,
    /// NC-1004: a feature the engine recognises but does not model (subprograms, macros...).
    NotModelled,
    /// NC-1005: a word given where the command does not allow it, or twice.
    IllegalWord,
    /// NC-1010: M29 repeated while rigid tapping mode is on.
    M29Repeated,
    /// NC-1011: axis move between M29 and G84/G88.
    AxisMoveAfterM29,
    /// NC-1012: the clamp M code of the tapping block is not the one of parameter 170.
    ClampCodeMismatch,
    /// NC-1013: tapping direction changed (G84 ↔ G88) without a new hole bottom.
    TapAxisChangedWithoutBottom,
    /// NC-1014: M29 and another M code in the same block.
    M29SharesBlock,
    /// NC-1015: RGTAP not on when the GSK rigid tapping cycle starts.
    RigidSignalOff,
    /// NC-1016: more than one M code in a block where the dialect allows one.
    TooManyMCodes,
    /// NC-1017: the spindle is not turning when a tapping cycle needs it.
    SpindleNotTurning,
    /// NC-1020: an M/S/T function's FIN never came within the PLC timer.
    FinTimeout,
    /// NC-1030: emergency stop.
    EmergencyStop,
    /// NC-1031: motor current overload during tapping: the tap was retracted.
    OverloadRetract,
    /// NC-1040: a machine parameter is out of its range (parameter change at run time).
    ParameterOutOfRange,
    /// NC-1050: `knd-lathe` G93: the tap, following the braking spindle, reached the end of the
    /// overshoot allowance (50 mm by default) before the spindle stopped.
    TapOvershoot,
    /// NC-1051: `knd-lathe` G93: the drive did not report zero speed (ZSP) within the timer after
    /// the spindle was braked or stopped: the cycle cannot reverse ("the tap never retracts").
    ZeroSpeedNotReported,
    /// NC-1060: `gsk-lathe` G92.3: the lead (F or I, or the lead reached through D) is out of
    /// range, zero or negative.
    ThreadLeadOutOfRange,
    /// NC-1061: `gsk-lathe` G92.3: the tool width A is above the smallest lead of the thread.
    ToolWidthAboveLead,
    /// NC-1062: `gsk-lathe` G92.3: the tip width E (or E + A) is above the smallest lead.
    TipWidthAboveLead,
    /// NC-1063: `gsk-lathe` G92.3: the axial step Q is 0 (or was never given).
    ThreadStepZero,
    /// NC-1064: `gsk-lathe` G92.3: the lead change per revolution D is out of its range.
    LeadChangeOutOfRange,
    /// NC-1065: `gsk-lathe` G92.3: a face thread (no travel along Z) is not allowed.
    FaceThread,
    /// NC-1120: an alarm recorded on a real control (`nc-conform check`) whose vendor code the
    /// engine does not know; the engine never raises it. Its detail is `<vendor code>: <text>`.
    UnknownVendorAlarm,
    /// NC-1090: `linuxcnc`: the interpreter refused a line (expression, parameter, o-word, word or
    /// mode error); the particulars are LinuxCNC's own text.
    LcncInterpreter,
    /// NC-1091: `linuxcnc`: a feed move or canned cycle with F0 ("Cannot feed with zero feed rate").
    LcncFeedZero,
    /// NC-1092: `linuxcnc`: the R plane is below the hole bottom ("R less than z in cycle in xy plane").
    LcncRBelowBottom,
    /// NC-1093: `linuxcnc`: a new canned cycle without R ("R clearance plane unspecified in cycle").
    LcncRUnspecified,
    /// NC-1094: `linuxcnc`: L0 in a canned cycle ("Cannot do zero repeats of cycle").
    LcncZeroRepeats,
    /// NC-1095: `linuxcnc`: the spindle is stopped or turns the wrong way for the cycle ("Spindle not
    /// turning in G84").
    LcncSpindle,
    /// NC-1096: `linuxcnc`: a word the cycle needs is missing ("Dwell time p word missing with g88",
    /// "K word missing with g33/g33.1").
    LcncWordMissing,
    /// NC-1097: `linuxcnc` G33.1: the tap, following the reversing spindle, reached 10 pitches past
    /// the end point.
    LcncTapOvershoot,
    /// NC-1098: `linuxcnc`: one block (an o-word loop or call) ran more lines or planned more steps
    /// than the engine's limit.
    LcncLoopLimit,
    /// NC-1070: `heidenhain`: a cycle parameter (`Q…`) is outside the range of its input (seed 004).
    QParamOutOfRange,
    /// NC-1071: `heidenhain`: a turning cycle is called outside `FUNCTION MODE TURN`.
    TurningModeRequired,
    /// NC-1072: `heidenhain`: `CYCL CALL` with no cycle defined before it.
    CycleNotDefined,
    /// NC-1073: `heidenhain` cycle 832: the taper dimensions give no thread (no length along the pitch, a taper angle that fixes no point, a point out of range).
    ThreadContourUndefined,
    /// NC-1074: `heidenhain` cycle 832: the infeed angle Q467 is larger than the thread's flank angle (seed 004 caution).
    InfeedAboveFlank,
    /// NC-1075: `heidenhain` cycle 832: the tool stands at a negative diameter when the cycle is called, which reverses Q471 (seed 004 caution).
    NegativeDiameterPreposition,
    /// NC-1076: `heidenhain` cycle 832: infeed type Q468 = 0 (constant chip section) with infeed angle Q467 = 0.
    ChipSectionNeedsAngle,
    /// NC-1077: A thread pass's feed (pitch x spindle speed) is above the maximum cutting feed.
    ThreadFeedTooHigh,
    /// NC-1078: A thread pass's approach (Q465) or overrun (Q466) path is shorter than the feed axis needs to reach or leave the thread feed.
    ThreadPathTooShort,
}

impl AlarmKind {
    /// Every alarm kind, in declaration order.
    pub const ALL: [AlarmKind; 58] = [
        AlarmKind::ImproperGCode,
        AlarmKind::FeedZero,
        AlarmKind::IllegalSCode,
        AlarmKind::FeedNotFoundRigid,
        AlarmKind::PositionLsiOverflow,
        AlarmKind::ProgramMissRigid,
        AlarmKind::IllegalAxisOperation,
        AlarmKind::RigidModeDiOff,
        AlarmKind::CannotChangePlane,
        AlarmKind::RigidDataMismatch,
        AlarmKind::ExcessErrorStopped,
        AlarmKind::ExcessErrorMoving,
        AlarmKind::M29FeedbackTimeout,
        AlarmKind::SpindleNotRotating,
        AlarmKind::WordOutOfRange,
        AlarmKind::WordMissing,
        AlarmKind::UnsupportedGCode,
        AlarmKind::NotModelled,
        AlarmKind::IllegalWord,
        AlarmKind::M29Repeated,
        AlarmKind::AxisMoveAfterM29,
        AlarmKind::ClampCodeMismatch,
        AlarmKind::TapAxisChangedWithoutBottom,
        AlarmKind::M29SharesBlock,
        AlarmKind::RigidSignalOff,
        AlarmKind::TooManyMCodes,
        AlarmKind::SpindleNotTurning,
        AlarmKind::FinTimeout,
        AlarmKind::EmergencyStop,
        AlarmKind::OverloadRetract,
        AlarmKind::ParameterOutOfRange,
        AlarmKind::TapOvershoot,
        AlarmKind::ZeroSpeedNotReported,
        AlarmKind::ThreadLeadOutOfRange,
        AlarmKind::ToolWidthAboveLead,
        AlarmKind::TipWidthAboveLead,
        AlarmKind::ThreadStepZero,
        AlarmKind::LeadChangeOutOfRange,
        AlarmKind::FaceThread,
        AlarmKind::UnknownVendorAlarm,
        AlarmKind::LcncInterpreter,
        AlarmKind::LcncFeedZero,
        AlarmKind::LcncRBelowBottom,
        AlarmKind::LcncRUnspecified,
        AlarmKind::LcncZeroRepeats,
        AlarmKind::LcncSpindle,
        AlarmKind::LcncWordMissing,
        AlarmKind::LcncTapOvershoot,
        AlarmKind::LcncLoopLimit,
        AlarmKind::QParamOutOfRange,
        AlarmKind::TurningModeRequired,
        AlarmKind::CycleNotDefined,
        AlarmKind::ThreadContourUndefined,
        AlarmKind::InfeedAboveFlank,
        AlarmKind::NegativeDiameterPreposition,
        AlarmKind::ChipSectionNeedsAngle,
        AlarmKind::ThreadFeedTooHigh,
        AlarmKind::ThreadPathTooShort,
    ];

    /// The alarm number as the trace writes it.
    pub fn code(self) -> &'static str {
        use AlarmKind::*;
        match self {
            ImproperGCode => "0010",
            FeedZero => "0011",
            IllegalSCode => "0200",
            FeedNotFoundRigid => "0201",
            PositionLsiOverflow => "0202",
            ProgramMissRigid => "0203",
            IllegalAxisOperation => "0204",
            RigidModeDiOff => "0205",
            CannotChangePlane => "0206",
            RigidDataMismatch => "0207",
            ExcessErrorStopped => "0410",
            ExcessErrorMoving => "0411",
            M29FeedbackTimeout => "5002",
            SpindleNotRotating => "5074",
            WordOutOfRange => "NC-1001",
            WordMissing => "NC-1002",
            UnsupportedGCode => "NC-1003",
            NotModelled => "NC-1004",
            IllegalWord => "NC-1005",
            M29Repeated => "NC-1010",
            AxisMoveAfterM29 => "NC-1011",
            ClampCodeMismatch => "NC-1012",
            TapAxisChangedWithoutBottom => "NC-1013",
            M29SharesBlock => "NC-1014",
            RigidSignalOff => "NC-1015",
            TooManyMCodes => "NC-1016",
            SpindleNotTurning => "NC-1017",
            FinTimeout => "NC-1020",
            EmergencyStop => "NC-1030",
            OverloadRetract => "NC-1031",
            ParameterOutOfRange => "NC-1040",
            TapOvershoot => "NC-1050",
            ZeroSpeedNotReported => "NC-1051",
            ThreadLeadOutOfRange => "NC-1060",
            ToolWidthAboveLead => "NC-1061",
            TipWidthAboveLead => "NC-1062",
            ThreadStepZero => "NC-1063",
            LeadChangeOutOfRange => "NC-1064",
            FaceThread => "NC-1065",
            UnknownVendorAlarm => "NC-1120",
            LcncInterpreter => "NC-1090",
            LcncFeedZero => "NC-1091",
            LcncRBelowBottom => "NC-1092",
            LcncRUnspecified => "NC-1093",
            LcncZeroRepeats => "NC-1094",
            LcncSpindle => "NC-1095",
            LcncWordMissing => "NC-1096",
            LcncTapOvershoot => "NC-1097",
            LcncLoopLimit => "NC-1098",
            QParamOutOfRange => "NC-1070",
            TurningModeRequired => "NC-1071",
            CycleNotDefined => "NC-1072",
            ThreadContourUndefined => "NC-1073",
            InfeedAboveFlank => "NC-1074",
            NegativeDiameterPreposition => "NC-1075",
            ChipSectionNeedsAngle => "NC-1076",
            ThreadFeedTooHigh => "NC-1077",
            ThreadPathTooShort => "NC-1078",
        }
    }

    /// The alarm's fixed title (the vendor's text where there is one).
    pub fn title(self) -> &'static str {
        use AlarmKind::*;
        match self {
            ImproperGCode => "IMPROPER G-CODE",
            FeedZero => "FEED ZERO",
            IllegalSCode => "ILLEGAL S CODE COMMAND",
            FeedNotFoundRigid => "FEEDRATE NOT FOUND IN RIGID TAP",
            PositionLsiOverflow => "POSITION LSI OVERFLOW",
            ProgramMissRigid => "PROGRAM MISS AT RIGID TAPPING",
            IllegalAxisOperation => "ILLEGAL AXIS OPERATION",
            RigidModeDiOff => "RIGID MODE DI SIGNAL OFF",
            CannotChangePlane => "CAN NOT CHANGE PLANE (RIGID TAP)",
            RigidDataMismatch => "RIGID DATA MISMATCH",
            ExcessErrorStopped => "EXCESS ERROR (STOP)",
            ExcessErrorMoving => "EXCESS ERROR (MOVE)",
            M29FeedbackTimeout => "FEEDBACK SIGNAL TIMEOUT AFTER M29",
            SpindleNotRotating => "SPINDLE NOT ROTATING IN RIGID TAPPING",
            WordOutOfRange => "WORD OUT OF RANGE",
            WordMissing => "WORD MISSING",
            UnsupportedGCode => "UNSUPPORTED G CODE",
            NotModelled => "NOT MODELLED",
            IllegalWord => "ILLEGAL WORD",
            M29Repeated => "M29 REPEATED IN RIGID TAPPING",
            AxisMoveAfterM29 => "AXIS MOVE BETWEEN M29 AND TAPPING CYCLE",
            ClampCodeMismatch => "CLAMP M CODE MISMATCH",
            TapAxisChangedWithoutBottom => "TAP AXIS CHANGED WITHOUT NEW BOTTOM",
            M29SharesBlock => "M29 SHARES BLOCK WITH ANOTHER M CODE",
            RigidSignalOff => "RIGID TAPPING SIGNAL RGTAP OFF",
            TooManyMCodes => "TOO MANY M CODES IN BLOCK",
            SpindleNotTurning => "SPINDLE NOT TURNING",
            FinTimeout => "FIN TIMEOUT",
            EmergencyStop => "EMERGENCY STOP",
            OverloadRetract => "OVERLOAD RETRACT",
            ParameterOutOfRange => "PARAMETER OUT OF RANGE",
            TapOvershoot => "TAP OVERSHOOT BEYOND ALLOWANCE",
            ZeroSpeedNotReported => "ZERO SPEED NOT REPORTED",
            ThreadLeadOutOfRange => "THREAD LEAD OUT OF RANGE",
            ToolWidthAboveLead => "TOOL WIDTH ABOVE MINIMUM LEAD",
            TipWidthAboveLead => "TIP WIDTH ABOVE MINIMUM LEAD",
            ThreadStepZero => "AXIAL STEP Q ZERO",
            LeadChangeOutOfRange => "LEAD CHANGE D OUT OF RANGE",
            FaceThread => "FACE THREAD NOT ALLOWED",
            UnknownVendorAlarm => "VENDOR ALARM UNKNOWN TO THE REFERENCE",
            LcncInterpreter => "LINUXCNC INTERPRETER ERROR",
            LcncFeedZero => "CANNOT FEED WITH ZERO FEED RATE",
            LcncRBelowBottom => "R LESS THAN BOTTOM IN CYCLE",
            LcncRUnspecified => "R CLEARANCE PLANE UNSPECIFIED IN CYCLE",
            LcncZeroRepeats => "CANNOT DO ZERO REPEATS OF CYCLE",
            LcncSpindle => "SPINDLE NOT TURNING AS THE CYCLE NEEDS",
            LcncWordMissing => "WORD MISSING WITH CYCLE",
            LcncTapOvershoot => "RIGID TAP OVERSHOOT BEYOND 10 PITCHES",
            LcncLoopLimit => "PROGRAM LOOP LIMIT",
            QParamOutOfRange => "CYCLE PARAMETER OUT OF RANGE",
            TurningModeRequired => "CYCLE NEEDS TURNING MODE",
            CycleNotDefined => "CYCL CALL WITHOUT CYCLE DEFINITION",
            ThreadContourUndefined => "THREAD CONTOUR UNDEFINED",
            InfeedAboveFlank => "INFEED ANGLE ABOVE FLANK ANGLE",
            NegativeDiameterPreposition => "NEGATIVE DIAMETER PRE-POSITION",
            ChipSectionNeedsAngle => "CONSTANT CHIP SECTION NEEDS INFEED ANGLE",
            ThreadFeedTooHigh => "THREAD FEED ABOVE MAXIMUM",
            ThreadPathTooShort => "APPROACH OR OVERRUN PATH TOO SHORT",
        }
    }
}

/// One raised alarm: kind, the particulars, and where in the program.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Alarm {
    /// What kind.
    pub kind: AlarmKind,
    /// The particulars ("P-1: dwell must be 0..99999999 ms").
    pub detail: String,
    /// Source line of the block that raised it, if any.
    pub line: Option<u32>,
    /// Column of the offending word, if any.
    pub col: Option<u32>,
}

impl Alarm {
    /// A new alarm without a location.
    pub fn new(kind: AlarmKind, detail: impl Into<String>) -> Self {
        Alarm { kind, detail: detail.into(), line: None, col: None }
    }

    /// Sets the location.
    pub fn at(mut self, line: u32, col: Option<u32>) -> Self {
        self.line = Some(line);
        self.col = col;
        self
    }

    /// The full message: title, particulars and location.
    pub fn message(&self) -> String {
        let loc = match (self.line, self.col) {
            (Some(l), Some(c)) => format!(" (line {l}, column {c})"),
            (Some(l), None) => format!(" (line {l})"),
            _ => String::new(),
        };
        if self.detail.is_empty() {
            format!("{}{loc}", self.kind.title())
        } else {
            format!("{}: {}{loc}", self.kind.title(), self.detail)
        }
    }
}
