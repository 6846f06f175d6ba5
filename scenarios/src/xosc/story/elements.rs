//! The storyboard's element state machine (OpenSCENARIO 1.3 User Guide, "Storyboard and
//! entities"): stories, acts, maneuver groups, maneuvers, events and actions built from the
//! file and moved through standby, running and complete on their triggers, with event
//! priorities (override, skip, parallel) and execution counts.

use super::*;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(in crate::xosc::story) enum Kind {
    Story,
    Act,
    Group,
    Maneuver,
    Event,
    Action,
}

impl Kind {
    pub(in crate::xosc::story) fn name(self) -> &'static str {
        match self {
            Kind::Story => "story",
            Kind::Act => "act",
            Kind::Group => "maneuverGroup",
            Kind::Maneuver => "maneuver",
            Kind::Event => "event",
            Kind::Action => "action",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(in crate::xosc::story) enum Phase {
    Standby,
    Running,
    Complete,
}

/// The transitions an element made in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(in crate::xosc::story) struct Moves {
    pub(in crate::xosc::story) start: bool,
    pub(in crate::xosc::story) end: bool,
    pub(in crate::xosc::story) stop: bool,
    pub(in crate::xosc::story) skip: bool,
}

/// A transition of the standard's element state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(in crate::xosc::story) enum Transition {
    Start,
    End,
    Stop,
    Skip,
}

/// A transition an element made: the storyboard's count of transitions made before it
/// ([`Storyboard::seq`]), which one, and the phase it left the element in. A condition on an
/// element's state reads the changes made since it was last evaluated, as esmini's
/// `TrigByState` queues each state change for its conditions until they next evaluate.
#[derive(Debug, Clone, Copy)]
pub(in crate::xosc::story) struct Change {
    pub(in crate::xosc::story) seq: u64,
    pub(in crate::xosc::story) what: Transition,
    pub(in crate::xosc::story) phase: Phase,
}

#[derive(Debug, Clone)]
pub(in crate::xosc::story) struct Elem {
    pub(in crate::xosc::story) kind: Kind,
    pub(in crate::xosc::story) name: String,
    pub(in crate::xosc::story) children: Vec<usize>,
    pub(in crate::xosc::story) phase: Phase,
    pub(in crate::xosc::story) runs: u32,
    pub(in crate::xosc::story) max_runs: u32,
    /// Entity tasks of an action still in flight.
    pub(in crate::xosc::story) pending: usize,
    pub(in crate::xosc::story) start: Option<usize>,
    pub(in crate::xosc::story) stop: Option<usize>,
    pub(in crate::xosc::story) priority: Priority,
    /// An action's action and the entities it acts on.
    pub(in crate::xosc::story) action: Option<(m::NamedAction, Vec<usize>)>,
    /// The transitions it made in this step (for the test's timeline).
    pub(in crate::xosc::story) moves: Moves,
    /// Its transitions, in order.
    pub(in crate::xosc::story) changes: Vec<Change>,
}

/// Whose trigger a trigger is, which says when it is evaluated: a start trigger while its
/// element waits in standby under a running parent, a stop trigger while its element runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(in crate::xosc::story) enum Owner {
    Storyboard,
    ActStart(usize),
    ActStop(usize),
    EventStart { event: usize, maneuver: usize },
}

impl Storyboard {
    /// Adds `act` under story element `s`: the act, its triggers, and its maneuver groups
    /// with their maneuvers, events and actions.
    ///
    /// # Errors
    /// [`StoryError`] for an action naming a road or lane the map lacks
    /// ([`Storyboard::check_references`]).
    pub(in crate::xosc::story) fn add_act(
        &mut self,
        s: usize,
        act: &m::Act,
    ) -> Result<(), StoryError> {
        let a = self.push(Kind::Act, &act.name, 1);
        self.elems[s].children.push(a);
        // An empty trigger (`<StartTrigger/>`) is no trigger: the act starts with
        // its story (esmini's reading); an empty stop trigger never fires.
        self.elems[a].start = act
            .start
            .as_ref()
            .filter(|t| !t.0.is_empty())
            .map(|t| self.add_trigger(t, Owner::ActStart(a)));
        self.elems[a].stop = act
            .stop
            .as_ref()
            .filter(|t| !t.0.is_empty())
            .map(|t| self.add_trigger(t, Owner::ActStop(a)));
        for g in &act.groups {
            let gi = self.push(Kind::Group, &g.name, g.max_count);
            self.elems[a].children.push(gi);
            for man in &g.maneuvers {
                let mi = self.push(Kind::Maneuver, &man.name, 1);
                self.elems[gi].children.push(mi);
                for ev in &man.events {
                    self.add_event(mi, ev, &g.actors)?;
                }
            }
        }
        Ok(())
    }

    /// Adds event `ev` under maneuver element `mi`: the event, its start trigger, and its
    /// actions, each acting on `actors` (its maneuver group's).
    ///
    /// # Errors
    /// [`StoryError`] for an action naming a road or lane the map lacks
    /// ([`Storyboard::check_references`]).
    pub(in crate::xosc::story) fn add_event(
        &mut self,
        mi: usize,
        ev: &m::Event,
        actors: &[usize],
    ) -> Result<(), StoryError> {
        let ei = self.push(Kind::Event, &ev.name, ev.max_count);
        self.elems[mi].children.push(ei);
        self.elems[ei].priority = ev.priority;
        self.elems[ei].start = ev.start.as_ref().filter(|t| !t.0.is_empty()).map(|t| {
            self.add_trigger(
                t,
                Owner::EventStart {
                    event: ei,
                    maneuver: mi,
                },
            )
        });
        for na in &ev.actions {
            self.check_references(na)?;
            let ai = self.push(Kind::Action, &na.name, 1);
            self.elems[ei].children.push(ai);
            self.elems[ai].action = Some((na.clone(), actors.to_vec()));
        }
        Ok(())
    }

    pub(in crate::xosc::story) fn push(&mut self, kind: Kind, name: &str, max_runs: u32) -> usize {
        self.elems.push(Elem {
            kind,
            name: name.to_owned(),
            children: Vec::new(),
            phase: Phase::Standby,
            runs: 0,
            max_runs: max_runs.max(1),
            pending: 0,
            start: None,
            stop: None,
            priority: Priority::Override,
            action: None,
            moves: Moves::default(),
            changes: Vec::new(),
        });
        self.elems.len() - 1
    }

    pub(in crate::xosc::story) fn add_trigger(&mut self, t: &m::Trigger, owner: Owner) -> usize {
        self.owners.push(owner);
        self.triggers.push(
            t.0.iter()
                .map(|g| g.iter().map(|c| Cond::new(c.clone())).collect())
                .collect(),
        );
        self.triggers.len() - 1
    }

    /// Whether trigger `k` is evaluated now: the storyboard's stop trigger always, a start
    /// trigger while its element waits in standby under a running parent, an act's stop
    /// trigger while the act runs.
    pub(in crate::xosc::story) fn waits(&self, k: usize) -> bool {
        match self.owners[k] {
            Owner::Storyboard => true,
            Owner::ActStart(a) => self.elems[a].phase == Phase::Standby,
            Owner::ActStop(a) => self.elems[a].phase == Phase::Running,
            Owner::EventStart { event, maneuver } => {
                self.elems[event].phase == Phase::Standby
                    && self.elems[maneuver].phase == Phase::Running
            }
        }
    }

    pub(in crate::xosc::story) fn run_story(&mut self, s: usize, t: f64) -> Result<(), StoryError> {
        // esmini's traversal (`StoryBoardElement::EvalTriggers`): each element's triggers
        // are evaluated when it is visited, a running act's stop trigger first, and an act
        // that starts has its events judged in the same visit, so that a condition sees what
        // the elements visited before it did in this step (a parameter set, a transition).
        for a in self.elems[s].children.clone() {
            if self.elems[a].phase == Phase::Running
                && self.elems[a].stop.is_some_and(|k| self.evaluate(k, t))
            {
                self.stop_elem(a);
                continue;
            }
            if self.elems[a].phase == Phase::Standby {
                if !self.elems[a].start.is_none_or(|k| self.evaluate(k, t)) {
                    continue;
                }
                self.start_elem(a, t)?;
                for g in self.elems[a].children.clone() {
                    self.start_group(g, t)?;
                }
            }
            if self.elems[a].phase == Phase::Running {
                for g in self.elems[a].children.clone() {
                    self.run_group(g, t)?;
                }
                self.settle(a);
            }
        }
        self.settle(s);
        Ok(())
    }

    /// Ends element `i` (a maneuver, an act or a story) when it runs and every child of it
    /// is complete.
    pub(in crate::xosc::story) fn settle(&mut self, i: usize) {
        if self.elems[i].phase == Phase::Running
            && self.elems[i]
                .children
                .iter()
                .all(|&c| self.elems[c].phase == Phase::Complete)
        {
            self.end_elem(i);
        }
    }

    /// Ends a running maneuver group `g` whose maneuvers are all complete, or starts it
    /// again while it has runs left (`maximumExecutionCount`).
    fn settle_group(&mut self, g: usize, t: f64) -> Result<(), StoryError> {
        let e = &self.elems[g];
        if e.phase != Phase::Running
            || !e
                .children
                .iter()
                .all(|&m| self.elems[m].phase == Phase::Complete)
        {
            return Ok(());
        }
        self.elems[g].runs += 1;
        if self.elems[g].runs < self.elems[g].max_runs {
            let runs = self.elems[g].runs;
            self.start_group(g, t)?;
            self.elems[g].runs = runs;
            // Run again, its events' triggers start afresh (esmini resets the children of
            // an element it runs again).
            for m in self.elems[g].children.clone() {
                for ev in self.elems[m].children.clone() {
                    if let Some(k) = self.elems[ev].start {
                        self.reset_trigger(k);
                    }
                }
            }
        } else {
            self.end_elem(g);
        }
        Ok(())
    }

    /// Carries the ends of this step's events up the storyboard, as esmini's
    /// `StoryBoardElement::End` ends a parent in the frame its last child ends
    /// (`PropagateStateFromChildren`): a maneuver whose events are all complete ends, then
    /// its group (or starts it again), its act and its story, so that a condition on their
    /// end sees it in the next step.
    pub(in crate::xosc::story) fn settle_all(&mut self, t: f64) -> Result<(), StoryError> {
        for s in self.roots.clone() {
            if self.elems[s].phase != Phase::Running {
                continue;
            }
            for a in self.elems[s].children.clone() {
                if self.elems[a].phase != Phase::Running {
                    continue;
                }
                for g in self.elems[a].children.clone() {
                    if self.elems[g].phase != Phase::Running {
                        continue;
                    }
                    for m in self.elems[g].children.clone() {
                        self.settle(m);
                    }
                    self.settle_group(g, t)?;
                }
                self.settle(a);
            }
            self.settle(s);
        }
        Ok(())
    }

    pub(in crate::xosc::story) fn start_group(
        &mut self,
        g: usize,
        t: f64,
    ) -> Result<(), StoryError> {
        self.start_elem(g, t)?;
        for man in self.elems[g].children.clone() {
            self.start_elem(man, t)?;
            for ev in self.elems[man].children.clone() {
                let e = &mut self.elems[ev];
                e.phase = Phase::Standby;
                e.runs = 0;
            }
        }
        Ok(())
    }

    pub(in crate::xosc::story) fn run_group(&mut self, g: usize, t: f64) -> Result<(), StoryError> {
        if self.elems[g].phase != Phase::Running {
            return Ok(());
        }
        for man in self.elems[g].children.clone() {
            self.run_maneuver(man, t)?;
        }
        self.settle_group(g, t)
    }

    pub(in crate::xosc::story) fn run_maneuver(
        &mut self,
        man: usize,
        t: f64,
    ) -> Result<(), StoryError> {
        if self.elems[man].phase != Phase::Running {
            return Ok(());
        }
        let events = self.elems[man].children.clone();
        for &ev in &events {
            if self.elems[ev].phase != Phase::Standby {
                continue;
            }
            if !self.elems[ev].start.is_none_or(|k| self.evaluate(k, t)) {
                continue;
            }
            let others: Vec<usize> = events
                .iter()
                .copied()
                .filter(|&o| o != ev && self.elems[o].phase == Phase::Running)
                .collect();
            match self.elems[ev].priority {
                Priority::Skip if !others.is_empty() => {
                    self.elems[ev].moves.skip = true;
                    self.record(ev, Transition::Skip);
                    continue;
                }
                Priority::Override => {
                    for o in others {
                        self.stop_elem(o);
                    }
                }
                _ => {}
            }
            self.start_elem(ev, t)?;
            self.elems[ev].runs += 1;
            for a in self.elems[ev].children.clone() {
                self.start_action(a, t)?;
            }
        }
        for &ev in &events {
            if self.elems[ev].phase == Phase::Running
                && self.elems[ev]
                    .children
                    .iter()
                    .all(|&a| self.elems[a].phase == Phase::Complete)
            {
                self.end_elem(ev);
                if self.elems[ev].runs < self.elems[ev].max_runs {
                    self.rearm(ev);
                }
            }
        }
        self.settle(man);
        Ok(())
    }

    pub(in crate::xosc::story) fn start_elem(
        &mut self,
        i: usize,
        _t: f64,
    ) -> Result<(), StoryError> {
        let e = &mut self.elems[i];
        e.phase = Phase::Running;
        e.moves.start = true;
        self.record(i, Transition::Start);
        Ok(())
    }

    pub(in crate::xosc::story) fn end_elem(&mut self, i: usize) {
        let e = &mut self.elems[i];
        if e.phase != Phase::Complete {
            e.phase = Phase::Complete;
            e.moves.end = true;
            self.record(i, Transition::End);
        }
    }

    /// Records that element `i` made transition `what` (in the phase it is in now).
    pub(in crate::xosc::story) fn record(&mut self, i: usize, what: Transition) {
        let phase = self.elems[i].phase;
        self.elems[i].changes.push(Change {
            seq: self.seq,
            what,
            phase,
        });
        self.seq += 1;
    }

    /// Event `ev`, ended with runs left, waits again: in standby (its end leaves it there),
    /// its start trigger's conditions reset (esmini's `StoryBoardElement::End` resets the
    /// trigger of an element it will run again).
    pub(in crate::xosc::story) fn rearm(&mut self, ev: usize) {
        self.elems[ev].phase = Phase::Standby;
        if let Some(c) = self.elems[ev].changes.last_mut() {
            c.phase = Phase::Standby;
        }
        if let Some(k) = self.elems[ev].start {
            self.reset_trigger(k);
        }
    }

    /// Forgets the transitions trigger `k`'s conditions have not read, and unlatches them
    /// (CARLA's reading, [`Storyboard::carla`]): its element waits afresh.
    pub(in crate::xosc::story) fn reset_trigger(&mut self, k: usize) {
        let now = self.seq;
        for c in self.triggers[k].iter_mut().flatten() {
            c.seen = now;
            c.latched = false;
        }
    }

    /// Stops element `i` and everything running below it (their entity tasks end).
    pub(in crate::xosc::story) fn stop_elem(&mut self, i: usize) {
        for c in self.elems[i].children.clone() {
            if self.elems[c].phase != Phase::Complete {
                self.stop_elem(c);
            }
        }
        if self.elems[i].kind == Kind::Action {
            for d in &mut self.drives {
                if d.speed.as_ref().is_some_and(|s| s.action == i) {
                    d.speed = None;
                }
                if d.lateral.as_ref().is_some_and(|l| l.action == i) {
                    d.lateral = None;
                }
                if d.path.as_ref().is_some_and(|s| s.1 == i) {
                    d.path = None;
                }
                if d.keep.as_ref().is_some_and(|k| k.action == i) {
                    d.keep = None;
                }
                if d.sync.as_ref().is_some_and(|s| s.action == i) {
                    d.sync = None;
                }
                if d.lat_keep.as_ref().is_some_and(|k| k.action == i) {
                    d.lat_keep = None;
                }
            }
            self.elems[i].pending = 0;
        }
        let e = &mut self.elems[i];
        e.phase = Phase::Complete;
        e.moves.stop = true;
        self.record(i, Transition::Stop);
    }

    pub(in crate::xosc::story) fn start_action(
        &mut self,
        a: usize,
        t: f64,
    ) -> Result<(), StoryError> {
        self.start_elem(a, t)?;
        let Some((action, actors)) = self.elems[a].action.clone() else {
            return Ok(());
        };
        if action.action.is_global() {
            // On the world, once, whoever the maneuver group's actors are; it completes in
            // this step, once every trigger has been read (esmini's global actions end in
            // their first `Step`).
            self.perform_global(&action, t)?;
            self.ending_now.push(a);
            return Ok(());
        }
        for e in actors {
            // An action that cannot be performed names itself and its entity.
            self.start_task(e, &action, Some(a), t)
                .map_err(|err| StoryError {
                    at: err.at,
                    message: format!(
                        "{} {:?} of {}: {}",
                        action.action.kind_name(),
                        action.name,
                        self.actors[e].name,
                        err.message
                    ),
                })?;
        }
        if self.elems[a].pending == 0 {
            // Done at once (a teleport, a lane's assignment): it completes in this step, once
            // every trigger has been read, as esmini's end in their first `Step`, after
            // every trigger's evaluation; a trigger reads that it completed in the next step.
            self.ending_now.push(a);
        }
        Ok(())
    }

    /// Completes the actions that were done when they started in this step
    /// ([`Storyboard::ending_now`]), after every trigger of the step has been read.
    pub(in crate::xosc::story) fn end_instant_actions(&mut self) {
        for a in std::mem::take(&mut self.ending_now) {
            if self.elems[a].phase == Phase::Running && self.elems[a].pending == 0 {
                self.end_elem(a);
            }
        }
    }

    /// A task of action `a` (an element, `None` in `Init`) ended.
    pub(in crate::xosc::story) fn task_done(&mut self, a: Option<usize>) {
        if let Some(a) = a {
            let e = &mut self.elems[a];
            e.pending = e.pending.saturating_sub(1);
            if e.pending == 0 && e.phase == Phase::Running {
                self.end_elem(a);
            }
        }
    }

    /// A task replaced by a new one of the same kind on the same entity ends (its action
    /// completes once all its tasks have).
    pub(in crate::xosc::story) fn override_task(&mut self, a: Option<usize>) {
        if let Some(a) = a.filter(|&a| a != usize::MAX) {
            self.task_done(Some(a));
        }
    }

    /// Entity `e`'s longitudinal tasks (a speed change, a kept distance, a synchronization)
    /// end, overridden by a new one (OpenSCENARIO 1.3, 7.4.2: one action per domain).
    pub(in crate::xosc::story) fn end_longitudinal(&mut self, e: usize) {
        let old = self.drives[e].speed.take().map(|s| s.action);
        self.override_task(old);
        let old = self.drives[e].keep.take().map(|k| k.action);
        self.override_task(old);
        let old = self.drives[e].sync.take().map(|s| s.action);
        self.override_task(old);
    }
}
