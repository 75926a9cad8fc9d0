//! [`Chooser`]: `auto`'s rules for which choice runs a frame, apart from
//! what the choices are. [`Auto`](super::Auto) chooses among culling
//! methods on any backend; a GPU-driven culler chooses among its late tests
//! by the same rules, with frame times read back some frames late. The
//! rules are described in [`super`]'s documentation.

use super::super::Carried;
use super::AutoParams;

/// Measured frames of a probe, after its warm-up frame.
const PROBE_FRAMES: u32 = 2;

/// Weight of the newest frame in the current choice's running mean.
const MEAN_WEIGHT: f64 = 0.25;

/// One choice, with its probe schedule.
#[derive(Clone, Debug)]
struct Choice {
    /// Frames it runs from nothing before one is measured; 0 for a choice
    /// that carries nothing from frame to frame, whose first frame needs
    /// no warm-up and whose probe is one measured frame.
    cold: u64,
    /// The shortest wait before its next probe, frames.
    wait: u64,
    /// First frame at which it may be probed.
    next_probe: u64,
    /// Its mean frame time when last measured (a probe, or its frames as
    /// the current choice), ms.
    last_time: Option<f64>,
    /// Frames it has run.
    frames: u64,
    /// Whether its first probe was put off until the budget covers the
    /// least its warm-up can cost ([`Bound::warm_up`]).
    deferred: bool,
}

/// Lower bounds of a choice's frame times, ms, where the caller knows them
/// ([`Chooser::begin`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// Of a frame once it runs warm: what its probe's measured frames cost
    /// at least.
    pub measured: f64,
    /// Of a frame from nothing: what each of its warm-up frames costs at
    /// least.
    pub warm_up: f64,
    /// Whether finding it added work to the frame (a walk of the
    /// hierarchy): that frame then measures no choice.
    pub costs_a_frame: bool,
}

/// A probe under way.
#[derive(Clone, Debug)]
struct Probe {
    choice: usize,
    /// Which probe this is: frames of an earlier one, recorded late, are
    /// not counted in it.
    serial: u64,
    /// Measured frame times, warm-up excluded.
    times: Vec<f64>,
    /// Its frames' time beyond the current choice's mean, warm-up
    /// included, ms.
    excess: f64,
    /// The least its measured frames cost ([`Bound::measured`]; 0 where
    /// unknown), ms.
    floor: f64,
}

/// What runs one frame ([`Chooser::begin`]); handed back with the frame's
/// time ([`Chooser::record`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ticket {
    /// The choice that runs the frame.
    pub choice: usize,
    /// Whether the frame is not measured: it only warms the choice up, or
    /// it also pays for finding a bound.
    warm_up: bool,
    /// The probe the frame belongs to, if any.
    probe: Option<u64>,
    /// The choice that ran the frame before, whose visibility this one
    /// starts from ([`Chooser::with_seeding`]).
    seed_from: Option<usize>,
}

impl Ticket {
    /// Whether the frame runs a probe rather than the current choice.
    pub fn is_probe(&self) -> bool {
        self.probe.is_some()
    }

    /// The choice whose last frame's visibility the frame's choice starts
    /// from, if any: the caller hands it over ([`Chooser::with_seeding`]).
    pub fn seed_from(&self) -> Option<usize> {
        self.seed_from
    }
}

/// `auto`'s choice among a fixed list of choices by measured frame time:
/// the current one runs; the others are probed now and then, within a
/// budget, and take over when faster by a margin.
#[derive(Clone, Debug)]
pub struct Chooser {
    params: AutoParams,
    choices: Vec<Choice>,
    /// The choice that culls nothing by occlusion (`vfc`), if among them:
    /// the others must beat it by the margin to stay current.
    baseline: Option<usize>,
    /// Per choice, the visibility it hands over and takes
    /// ([`Chooser::with_seeding`]).
    seeding: Vec<Carried>,
    current: usize,
    /// The current choice's running mean frame time, ms.
    mean: Option<f64>,
    probe: Option<Probe>,
    probes_begun: u64,
    last_ran: Option<usize>,
    /// Frames begun.
    begun: u64,
}

impl Chooser {
    /// A chooser among `cold.len()` choices, tried first in that order (the
    /// first is current until measured), choice `i` running `cold[i]`
    /// frames from nothing before one is measured (0: it carries nothing
    /// from frame to frame); `baseline` is the choice without occlusion
    /// culling, if any, which the others must beat by the margin to stay
    /// current. At least one choice.
    pub fn new(params: AutoParams, cold: &[u64], baseline: Option<usize>) -> Self {
        assert!(!cold.is_empty(), "a chooser needs a choice");
        let choices: Vec<Choice> = cold
            .iter()
            .map(|&cold| Choice {
                cold,
                wait: u64::from(params.probe),
                next_probe: 0,
                last_time: None,
                frames: 0,
                deferred: false,
            })
            .collect();
        Self {
            params,
            seeding: vec![Carried::Nothing; choices.len()],
            choices,
            baseline,
            current: 0,
            mean: None,
            probe: None,
            probes_begun: 0,
            last_ran: None,
            begun: 0,
        }
    }

    /// Says what visibility each choice carries from frame to frame
    /// (`seeding[i]` for choice `i`). Run right after another choice that
    /// carries some, one that carries some too starts from what that one
    /// found visible last frame ([`Ticket::seed_from`]). From a set of
    /// exactly the instances found visible ([`Carried::Instances`]) it is
    /// warm at once: that frame is measured. From a coarser set (by leaf),
    /// which draws more than a warm frame would, one frame warms it up, as
    /// after any other switch; from nothing a choice may need more.
    pub fn with_seeding(mut self, seeding: &[Carried]) -> Self {
        assert_eq!(seeding.len(), self.choices.len(), "one entry per choice");
        self.seeding = seeding.to_vec();
        self
    }

    /// The choice whose visibility `choice`, were it run next, would start
    /// from ([`Chooser::with_seeding`]): the one that ran the last frame, if
    /// another and both carry visibility.
    pub fn seed_source(&self, choice: usize) -> Option<usize> {
        let carries = |c: usize| self.seeding[c] != Carried::Nothing;
        self.last_ran.filter(|&p| p != choice && carries(p) && carries(choice))
    }

    /// The choice frames run when no probe does.
    pub fn current(&self) -> usize {
        self.current
    }

    /// The current choice's running mean frame time, ms, once measured.
    pub fn mean(&self) -> Option<f64> {
        self.mean
    }

    /// Begins a frame: the choice due for a probe, if any, else the
    /// current one. `bound(choice, mean, seeded)` may give lower bounds of
    /// a due choice's frame times ([`Bound`]), where the caller knows them;
    /// `seeded`: the choice would start from another's visibility
    /// ([`Chooser::seed_source`]), not from nothing. A
    /// measured bound no faster than the current `mean` by the margin puts
    /// the probe off as if it had lost at that time, sparing its frames;
    /// a choice never tried whose warm-up must cost more than `mean` is
    /// first tried once the budget covers that much.
    pub fn begin(&mut self, bound: impl FnOnce(usize, f64, bool) -> Option<Bound>) -> Ticket {
        let frame = self.begun;
        let mut bounded = false;
        if self.probe.is_none() {
            if let Some((choice, mean)) = self.due().zip(self.mean) {
                let c = &self.choices[choice];
                let first = c.last_time.is_none() && !c.deferred;
                let b = bound(choice, mean, self.seed_source(choice).is_some());
                bounded = b.is_some_and(|b| b.costs_a_frame);
                match b {
                    Some(b) if !self.wins(choice, b.measured, mean) => self.schedule(choice, b.measured, 0.0, frame),
                    Some(b) if first && b.warm_up > mean && c.cold > 0 => {
                        let wait = self.budget_wait(c.cold as f64 * (b.warm_up - mean), mean);
                        let c = &mut self.choices[choice];
                        c.deferred = true;
                        c.next_probe = frame + wait;
                    }
                    _ => {
                        self.probes_begun += 1;
                        let serial = self.probes_begun;
                        let floor = b.map_or(0.0, |b| b.measured);
                        self.probe = Some(Probe { choice, serial, times: Vec::new(), excess: 0.0, floor });
                    }
                }
            }
        }
        let choice = self.probe.as_ref().map_or(self.current, |p| p.choice);
        let seed_from = self.seed_source(choice);
        let warm_seed = seed_from.is_some_and(|s| self.seeding[s] == Carried::Instances);
        let c = &mut self.choices[choice];
        if seed_from.is_some() {
            // Seeded, it has what its frames from nothing would have found.
            c.frames = c.frames.max(c.cold);
        }
        let cold = c.frames < c.cold || (self.last_ran != Some(choice) && !warm_seed);
        // A frame that also pays for finding a bound (the caller's work,
        // such as a walk of the hierarchy) measures no choice.
        let warm_up = bounded || (c.cold > 0 && cold);
        c.frames += 1;
        self.last_ran = Some(choice);
        self.begun += 1;
        Ticket { choice, warm_up, probe: self.probe.as_ref().map(|p| p.serial), seed_from }
    }

    /// Records `time` ms for the frame `ticket` began. A frame of a probe
    /// that has ended, or of a choice no longer current, counts for
    /// nothing (its time came back late).
    pub fn record(&mut self, ticket: Ticket, time: f64) {
        let mean = self.mean;
        match self.probe.as_mut() {
            Some(probe) if ticket.probe == Some(probe.serial) => {
                probe.excess += mean.map_or(0.0, |m| time - m);
                if !ticket.warm_up {
                    probe.times.push(time);
                }
            }
            _ if ticket.probe.is_none() && ticket.choice == self.current && !ticket.warm_up => {
                self.mean = Some(mean.map_or(time, |m| m + MEAN_WEIGHT * (time - m)));
            }
            _ => return,
        }
        let Some(probe) = &self.probe else { return };
        let needed = if self.choices[probe.choice].cold == 0 { 1 } else { PROBE_FRAMES };
        // A probe that cannot win even if its frames to come cost their
        // least is decided: it ends at once.
        let measured = probe.times.len() as u32;
        let to_come = f64::from(needed.saturating_sub(measured)) * probe.floor;
        let best = (probe.times.iter().sum::<f64>() + to_come) / f64::from(needed.max(measured));
        let lost = measured > 0 && mean.is_some_and(|m| !self.wins(probe.choice, best, m));
        if measured >= needed || lost {
            let probe = self.probe.take().expect("checked above");
            self.end_probe(probe);
        }
    }

    fn margin(&self) -> f64 {
        f64::from(self.params.margin)
    }

    /// Whether `choice`, measured at `time` ms, takes over from the current
    /// choice at `mean` ms. Occlusion culling must pay for itself by the
    /// margin: a choice beats the current one by the margin, except the
    /// baseline, which takes over unless the current choice beats it by
    /// the margin. Either way a choice with occlusion culling runs only
    /// while it was measured faster than the baseline by the margin, and a
    /// choice taken over is not taken back without a change of times.
    fn wins(&self, choice: usize, time: f64, mean: f64) -> bool {
        if Some(choice) == self.baseline {
            mean > time * (1.0 - self.margin())
        } else {
            time < mean * (1.0 - self.margin())
        }
    }

    /// The latest frame begun.
    fn now(&self) -> u64 {
        self.begun.saturating_sub(1)
    }

    /// Sets when `choice`, last measured at `time` ms, is next tried: after
    /// its wait from `frame`, and late enough that a probe costing `excess`
    /// ms beyond the current mean stays within its share of the budget
    /// ([`Chooser::budget_wait`]). Its wait doubles.
    fn schedule(&mut self, choice: usize, time: f64, excess: f64, frame: u64) {
        let budget_wait = self.budget_wait(excess, self.mean.unwrap_or(time));
        let c = &mut self.choices[choice];
        c.last_time = Some(time);
        c.next_probe = frame + c.wait.max(budget_wait);
        c.wait = c.wait.saturating_mul(2);
    }

    /// Frames a probe costing `excess` ms beyond a current mean of `mean`
    /// ms must wait for its share of the budget to cover it (the budget is
    /// split evenly among the choices other than the current one).
    fn budget_wait(&self, excess: f64, mean: f64) -> u64 {
        let others = self.choices.len().saturating_sub(1).max(1) as f64;
        let per_frame = f64::from(self.params.budget) * mean / others;
        if per_frame > 0.0 {
            (excess.max(0.0) / per_frame).ceil() as u64
        } else {
            0
        }
    }

    /// Ends a probe: the probed choice takes over if it beat the current
    /// one by the margin; the one left waits for its next probe.
    fn end_probe(&mut self, probe: Probe) {
        let probed = probe.times.iter().sum::<f64>() / probe.times.len() as f64;
        let mean = self.mean.unwrap_or(probed);
        let now = self.now();
        if self.wins(probe.choice, probed, mean) {
            let previous = std::mem::replace(&mut self.current, probe.choice);
            self.mean = Some(probed);
            let frames = if self.choices[previous].cold == 0 { 1.0 } else { f64::from(PROBE_FRAMES + 1) };
            self.schedule(previous, mean, frames * (mean - probed), now);
        } else {
            self.schedule(probe.choice, probed, probe.excess, now);
        }
    }

    /// The choice due for a probe now, if any: one whose wait is over, or
    /// one last measured faster than the current choice is now (the
    /// current one has stopped paying). One that would start from another's
    /// visibility goes first, its try being the shorter; then the earliest
    /// due.
    fn due(&self) -> Option<usize> {
        let mean = self.mean?;
        // A lost probe left the mean at most `1 / (1 - margin)` of the
        // probe's time: only a mean grown past that by the margin again
        // calls for a new probe, not one that stood still.
        let slack = (1.0 + self.margin()) / (1.0 - self.margin());
        let overtaken = |c: &Choice| c.last_time.is_some_and(|t| mean > t * slack);
        (0..self.choices.len())
            .filter(|&c| c != self.current)
            .filter(|&c| self.choices[c].next_probe <= self.begun || overtaken(&self.choices[c]))
            .min_by_key(|&c| (self.seed_source(c).is_none(), self.choices[c].next_probe))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a chooser among choices costing `costs` ms (choice 0 first, all
    /// keeping state) for `frames` frames, each frame's time recorded
    /// `delay` frames after it began; returns the choice of each frame.
    fn run(costs: &[f64], frames: usize, delay: usize) -> Vec<usize> {
        let mut chooser = Chooser::new(AutoParams::default(), &vec![2; costs.len()], None);
        let mut pending = std::collections::VecDeque::new();
        let mut ran = Vec::new();
        for _ in 0..frames {
            let ticket = chooser.begin(|_, _, _| None);
            ran.push(ticket.choice);
            pending.push_back(ticket);
            if pending.len() > delay {
                let t = pending.pop_front().unwrap();
                chooser.record(t, costs[t.choice]);
            }
        }
        ran
    }

    #[test]
    fn times_read_back_late_still_find_the_fastest() {
        for delay in [0, 3] {
            let ran = run(&[2.0, 3.0, 1.0], 400, delay);
            let late = ran[100..].iter().filter(|&&c| c == 2).count();
            assert!(late as f64 > 0.97 * 300.0, "delay {delay}: the fastest ran {late} of 300 frames");
        }
    }

    #[test]
    fn a_late_time_of_an_ended_probe_counts_for_nothing() {
        let mut chooser = Chooser::new(AutoParams::default(), &[0, 0], None);
        let first = chooser.begin(|_, _, _| None);
        chooser.record(first, 1.0);
        // Choice 1 is due at once (never measured): one frame probes it.
        let probe = chooser.begin(|_, _, _| None);
        assert!(probe.is_probe() && probe.choice == 1);
        chooser.record(probe, 3.0);
        assert_eq!(chooser.current(), 0);
        // The same frame's time again, late, changes nothing.
        let before = chooser.clone();
        chooser.record(probe, 0.1);
        assert_eq!((chooser.current(), chooser.mean()), (before.current(), before.mean()));
    }

    /// Runs a chooser between an occlusion culler costing `culling` ms a
    /// frame (tried first, warm after two frames) and the baseline costing
    /// 1 ms for 400 frames; returns the frames the culler ran of the last
    /// 300.
    fn culler_frames(culling: f64) -> usize {
        let mut chooser = Chooser::new(AutoParams::default(), &[2, 0], Some(1));
        let ran: Vec<usize> = (0..400)
            .map(|_| {
                let t = chooser.begin(|_, _, _| None);
                chooser.record(t, if t.choice == 0 { culling } else { 1.0 });
                t.choice
            })
            .collect();
        ran[100..].iter().filter(|&&c| c == 0).count()
    }

    #[test]
    fn occlusion_culling_stays_only_while_it_beats_the_baseline_by_the_margin() {
        // 2 % faster than the baseline: not worth keeping; the baseline
        // runs but for its probes.
        assert!(culler_frames(0.98) < 10, "{}", culler_frames(0.98));
        // 10 % faster: it stays.
        assert!(culler_frames(0.90) > 290, "{}", culler_frames(0.90));
        // Without a baseline, a choice 2 % faster than the current one
        // stays current.
        let mut chooser = Chooser::new(AutoParams::default(), &[2, 0], None);
        for _ in 0..400 {
            let t = chooser.begin(|_, _, _| None);
            chooser.record(t, if t.choice == 0 { 0.98 } else { 1.0 });
        }
        assert_eq!(chooser.current(), 0);
    }

    /// A chooser between two stateless choices whose first, choice 0, ran
    /// one frame of 1 ms; choice 1 is due.
    fn choice_0_at_1_ms() -> Chooser {
        let mut chooser = Chooser::new(AutoParams::default(), &[0, 0], None);
        let first = chooser.begin(|_, _, _| None);
        chooser.record(first, 1.0);
        chooser
    }

    /// Choice 1's bound at twice the current mean: it cannot win.
    fn choice_1_cannot_win(choice: usize, mean: f64, _: bool) -> Option<Bound> {
        (choice == 1).then_some(Bound { measured: mean * 2.0, warm_up: mean * 2.0, costs_a_frame: true })
    }

    #[test]
    fn a_bound_that_cannot_win_spares_the_probe() {
        let next = choice_0_at_1_ms().begin(choice_1_cannot_win);
        assert_eq!((next.choice, next.is_probe()), (0, false));
    }

    #[test]
    fn a_frame_that_finds_a_bound_measures_no_choice() {
        // The frame that found choice 1's bound costs 5 ms (the bound's
        // walk), which is not choice 0's time.
        let mut chooser = choice_0_at_1_ms();
        let bounded = chooser.begin(choice_1_cannot_win);
        assert_eq!((bounded.choice, bounded.is_probe()), (0, false));
        chooser.record(bounded, 5.0);
        assert_eq!(chooser.mean(), Some(1.0));
        // The next frame is measured again.
        let next = chooser.begin(choice_1_cannot_win);
        chooser.record(next, 2.0);
        assert_eq!(chooser.mean(), Some(1.25));
        // A bound found without work leaves its frame measured.
        let mut chooser = choice_0_at_1_ms();
        let free = chooser.begin(|c, m, s| choice_1_cannot_win(c, m, s).map(|b| Bound { costs_a_frame: false, ..b }));
        chooser.record(free, 2.0);
        assert_eq!(chooser.mean(), Some(1.25));
    }

    #[test]
    fn a_first_try_waits_until_the_budget_covers_its_least_warm_up() {
        // Choice 1 might win once warm, but its warm-up frame costs at
        // least 3 ms where the current choice takes 1: its first probe
        // waits until 1 % of 1 ms a frame has paid the 2 ms beyond.
        let mut chooser = Chooser::new(AutoParams::default(), &[0, 1], None);
        let first = chooser.begin(|_, _, _| None);
        chooser.record(first, 1.0);
        let bound = Bound { measured: 0.5, warm_up: 3.0, costs_a_frame: false };
        let mut waited = 0;
        loop {
            let t = chooser.begin(|_, _, _| Some(bound));
            if t.is_probe() {
                break;
            }
            chooser.record(t, 1.0);
            waited += 1;
        }
        assert_eq!(waited, 201, "the frame that put it off, then 2 ms of excess at 0.01 ms a frame");
    }

    /// Choice 1 (two frames from nothing) probed against choice 0 at 1 ms,
    /// its measured frames bounded below by `floor` ms (none: `None`), its
    /// first measured frame taking `first` ms: whether the frame after that
    /// one still probes it.
    fn probe_goes_on(floor: Option<f64>, first: f64) -> bool {
        let mut chooser = choice_0_at_1_ms();
        chooser.choices[1].cold = 2;
        let bound = |_, _, _| floor.map(|f| Bound { measured: f, warm_up: f, costs_a_frame: false });
        for time in [3.0, 3.0, first] {
            let t = chooser.begin(bound);
            assert!(t.is_probe() && t.choice == 1);
            chooser.record(t, time);
        }
        chooser.begin(bound).is_probe()
    }

    #[test]
    fn a_probe_ends_once_its_frames_to_come_cannot_make_it_win() {
        // Two measured frames must average under 0.95 ms. After 1 ms, a
        // second frame of at least 0.9 cannot do it; one of 0.5 can.
        assert!(!probe_goes_on(Some(0.9), 1.0));
        assert!(probe_goes_on(Some(0.5), 1.0));
        // Without a bound, the next frame might take no time at all.
        assert!(probe_goes_on(None, 1.8));
        assert!(!probe_goes_on(None, 1.9));
    }

    #[test]
    fn a_choice_that_would_start_seeded_is_tried_before_one_from_nothing() {
        // Choices 1 and 2 are both due after choice 0's first frames; 2
        // would start from choice 0's visibility, 1 from nothing.
        let seeding = [Carried::Instances, Carried::Nothing, Carried::Instances];
        let mut chooser = Chooser::new(AutoParams::default(), &[2, 2, 2], None).with_seeding(&seeding);
        let ran: Vec<_> = (0..4)
            .map(|_| {
                let t = chooser.begin(|_, _, _| None);
                chooser.record(t, 1.0);
                (t.choice, t.seed_from())
            })
            .collect();
        assert_eq!(ran, [(0, None), (0, None), (0, None), (2, Some(0))]);
    }

    /// Runs a chooser among choices 0 and 1, carrying `carried`, and the
    /// baseline 2 (nothing), 0 and 1 needing two frames from nothing, for
    /// nine frames; returns each frame's choice, whether it warmed up, and
    /// its seed's source.
    fn seeded_run(carried: [Carried; 2]) -> Vec<(usize, bool, Option<usize>)> {
        let seeding = [carried[0], carried[1], Carried::Nothing];
        let mut chooser = Chooser::new(AutoParams::default(), &[2, 2, 0], Some(2)).with_seeding(&seeding);
        (0..9)
            .map(|_| {
                let t = chooser.begin(|_, _, _| None);
                chooser.record(t, [1.0, 1.5, 3.0][t.choice]);
                (t.choice, t.warm_up, t.seed_from())
            })
            .collect()
    }

    #[test]
    fn a_choice_seeded_from_exact_visibility_is_measured_at_once() {
        // Choice 0 from nothing: two frames warm up. Choice 1, right after
        // it, starts from the instances it found visible: measured at once.
        // The baseline takes nothing; choice 0 after it warms up one frame
        // from what it knew.
        let run = seeded_run([Carried::Instances, Carried::Instances]);
        let expected = [(0, true, None), (0, true, None), (0, false, None), (1, false, Some(0)), (1, false, None)];
        assert_eq!(run[..5], expected);
        assert_eq!(run[5..7], [(2, false, None), (0, true, None)]);
    }

    #[test]
    fn a_choice_seeded_from_coarser_visibility_warms_up_one_frame() {
        // Choice 0's set is by leaf: choice 1 warms up one frame from it.
        let run = seeded_run([Carried::Leaves, Carried::Instances]);
        let expected = [(0, true, None), (0, true, None), (0, false, None), (1, true, Some(0)), (1, false, None)];
        assert_eq!(run[..5], expected);
    }
}
