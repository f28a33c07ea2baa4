//! The parts of the comparison that take what the replay alongside sends with the reference's
//! samples (DEC-162): its discrete events for the matcher, its key points for the stroke by
//! stroke comparison, and the attribution of divergences at times whose moves and phases are no
//! longer held.

use super::super::events::Key;
use super::super::keypoints::KeyPoints;
use super::super::tolerance::{attribute, ms_us, Context, Topic};
use super::{Comparator, Divergence};

impl Comparator<'_, '_> {
    /// The widest event window, for the reference's discrete events taken from its feed.
    pub(in crate::check) fn widest_window(mut self) -> Self {
        let w = self.tol.event_windows_ms.values().fold(self.tol.event_ms, |a, &b| a.max(b));
        self.wmax = ms_us(w).max(0);
        self
    }

    /// The reference's key points, when they are not read alongside (streamed).
    pub(in crate::check) fn reference_keys(mut self) -> Self {
        if !self.r.streamed {
            let mut keys = self.r.keys.clone();
            self.keycmp.ref_reversals = keys.reversals;
            self.add_keys(0, &mut keys);
        }
        self
    }

    /// Key points of the reference (`side` 0) or the recording (1) for the stroke by stroke
    /// comparison.
    pub(in crate::check) fn add_keys(&mut self, side: usize, keys: &mut KeyPoints) {
        let mut kc = std::mem::take(&mut self.keycmp);
        kc.add(self, side, keys);
        self.keycmp = kc;
    }

    /// The recording's key points read so far that will not change, compared.
    pub(in crate::check) fn take_recorded_keys(&mut self) {
        if self.keys.has_final() {
            let mut keys = KeyPoints::default();
            self.keys.take(&mut keys);
            self.add_keys(1, &mut keys);
        }
    }

    /// The reference's discrete events pulled with its samples, given to the matcher (up to
    /// `t` + the widest window at least, when `t` is given: a recorded event at `t` is matched
    /// as against all of them).
    pub(in crate::check) fn take_reference_events(&mut self, t: Option<i64>) {
        if !self.r.streamed {
            return;
        }
        let mut w = self.r.win.borrow_mut();
        if let Some(t) = t {
            w.ensure(t.saturating_add(self.wmax));
        }
        if !(w.keys.segments.is_empty() && w.keys.returns.is_empty()) {
            let mut keys = std::mem::take(&mut w.keys);
            drop(w);
            self.add_keys(0, &mut keys);
            w = self.r.win.borrow_mut();
        }
        if w.keyed.is_empty() {
            return;
        }
        if let Some(m) = &mut self.matcher {
            for (tr, k) in w.keyed.drain(..) {
                match k {
                    Key::Edge(s, _) if self.carried.closed && !self.carried.declares(s) => {
                        match self.absent_refs.iter_mut().find(|x| x.0 == k) {
                            Some(x) => x.1 += 1,
                            None => self.absent_refs.push((k, 1, tr)),
                        }
                    }
                    _ => m.reference(k, tr),
                }
            }
        } else {
            w.keyed.clear();
        }
    }

    /// The attribution context at `t` from what a later replay found there (`Sweep`).
    pub(in crate::check) fn context_from(&self, t: i64, m: super::super::sync_stream::Moment) -> Context {
        Context {
            dialect: self.dialect.clone(),
            inputs: self.r.inputs_at(t),
            overload: self.r.overload_by(t + ms_us(self.tol.envelope_ms).max(ms_us(self.tol.event_ms))),
            scenario_rules: self.rules.clone(),
            phase: Some(m.0),
            sync_rule: m.1.and_then(|code| super::super::tolerance::sync_rule(&self.dialect, code)),
            in_sync: m.1.is_some(),
        }
    }

    /// The rule that `topic` breaks at `t`, when what attribution needs there is still held.
    pub(in crate::check) fn attribute_now(&self, topic: Topic, t: i64) -> Option<String> {
        self.r.holds_context_at(t).then(|| attribute(topic, &self.context(t)))
    }

    /// Attributes the divergences found at times whose context was dropped: one more replay
    /// of the reference reads its phases and synchronised moves there.
    pub(in crate::check) fn attribute_late(&mut self) {
        if self.unattributed.is_empty() {
            return;
        }
        let mut late = std::mem::take(&mut self.unattributed);
        late.sort_by_key(|x| x.2);
        let times = late.iter().map(|x| x.2).collect();
        let moments = super::super::sync_stream::Sweep::new(self.r.tap, times).run(self.r.source);
        for ((i, topic, t, overload), m) in late.into_iter().zip(moments) {
            let mut ctx = self.context_from(t, m);
            ctx.overload |= overload;
            let rule = attribute(topic, &ctx);
            if let Some(d) = self.divergences.get_mut(i) {
                d.rule = rule;
            }
        }
    }

    /// Adds a divergence whose rule is `rule`, or, when None, attributed at the end to `topic`
    /// at its time ([`Comparator::attribute_now`]).
    pub(in crate::check) fn push_attributed(
        &mut self,
        mut d: Divergence,
        rule: Option<String>,
        topic: Topic,
        overload: bool,
    ) {
        let late = rule.is_none();
        d.rule = rule.unwrap_or_default();
        let t = d.t_us.unwrap_or(0);
        if let (Some(i), true) = (self.push(d), late) {
            self.unattributed.push((i, topic, t, overload));
        }
    }

    /// Counts a divergence of `check` left out as [`Comparator::push`] leaves one out past
    /// [`super::MAX_PER_CHECK`].
    pub(in crate::check) fn omit(&mut self, check: &str) {
        *self.per_check.entry(check.to_string()).or_insert(0) += 1;
        self.omitted += 1;
        *self.omitted_by_check.entry(check.to_string()).or_insert(0) += 1;
    }

    /// The reference's key points: segments and returns.
    pub(in crate::check) fn key_counts(&self) -> (usize, usize) {
        (self.keycmp.segments(0), self.keycmp.returns(0))
    }
}
