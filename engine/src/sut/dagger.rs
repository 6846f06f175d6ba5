//! A learner that drives while a teacher labels: the data collection of DAgger (Ross, Gordon
//! and Bagnell 2011, "A Reduction of Imitation Learning and Structured Prediction to No-Regret
//! Online Learning", AISTATS, §3). A network cloned from a teacher's drives has seen only the
//! teacher's states; its own small errors take it to states it has never seen (a junction
//! taken too fast, a lane edge) and they compound. Here the learner drives, so the recorded
//! frames are the learner's states, and the teacher's answer for each of them is the label
//! ([`Sut::label`]).

use rand::{Rng, SeedableRng};

use super::{Sensors, Sut, SutError};
use crate::{Control, Observation};

/// Drives as `learner`, except that each decision applies `teacher`'s answer instead with
/// probability `beta` (DAgger's mixture policy, §3 of the article); the teacher is asked at
/// every decision and its answer is [`Sut::label`].
///
/// Sensors: the learner's (its camera and rate of decision); the teacher sees the same
/// observation, so a teacher that needs a camera the learner lacks sees none.
pub struct Dagger {
    learner: Box<dyn Sut>,
    teacher: Box<dyn Sut>,
    beta: f64,
    rng: rand_chacha::ChaCha8Rng,
    label: Option<Control>,
}

impl Dagger {
    /// `learner` drives, `teacher` labels; `beta` in `[0, 1]` is the probability that a
    /// decision applies the teacher's answer (0: the learner always drives). Another `beta`
    /// is refused by [`Sut::reset`].
    pub fn new(learner: Box<dyn Sut>, teacher: Box<dyn Sut>, beta: f64) -> Self {
        Dagger {
            learner,
            teacher,
            beta,
            rng: rand_chacha::ChaCha8Rng::seed_from_u64(0),
            label: None,
        }
    }
}

impl Sut for Dagger {
    fn sensors(&self) -> Sensors {
        let mut s = self.learner.sensors();
        s.frame_use = crate::FrameUse::ALL;
        s
    }

    fn reset(&mut self, seed: u64) -> Result<(), SutError> {
        if !(0.0..=1.0).contains(&self.beta) {
            return Err(SutError::Failed(format!(
                "the teacher's share {} must be in [0, 1]",
                self.beta
            )));
        }
        self.label = None;
        self.rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x6461_6767_6572_0001);
        self.teacher.reset(seed)?;
        self.learner.reset(seed)
    }

    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError> {
        let label = self.teacher.act(obs)?;
        let driven = self.learner.act(obs)?;
        self.label = Some(label);
        // One draw per decision whatever beta is, so the stream does not depend on it.
        let teacher_drives = self.rng.random::<f64>() < self.beta;
        Ok(if teacher_drives { label } else { driven })
    }

    fn label(&self) -> Option<Control> {
        self.label
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sut::ConstantControl;
    use crate::EgoState;

    fn obs() -> Observation<'static> {
        Observation {
            t_s: 0.0,
            dt_s: 1.0 / 60.0,
            ego: EgoState {
                pos_m: [0.0, 0.5, 0.0],
                heading_rad: 0.0,
                speed_mps: 1.0,
            },
            route: &[],
            set_speed_mps: None,
            readings: Vec::new(),
        }
    }

    const LEARNER: Control = Control {
        throttle: 0.2,
        steering: 0.3,
    };
    const TEACHER: Control = Control {
        throttle: -0.4,
        steering: -0.1,
    };

    fn dagger(beta: f64) -> Dagger {
        Dagger::new(
            Box::new(ConstantControl(LEARNER)),
            Box::new(ConstantControl(TEACHER)),
            beta,
        )
    }

    #[test]
    fn the_learner_drives_and_the_teacher_labels() {
        let mut d = dagger(0.0);
        d.reset(3).unwrap();
        assert_eq!(d.label(), None, "no label before the first decision");
        for _ in 0..20 {
            assert_eq!(d.act(&obs()).unwrap(), LEARNER);
            assert_eq!(d.label(), Some(TEACHER));
        }
        let mut d = dagger(1.0);
        d.reset(3).unwrap();
        assert_eq!(d.act(&obs()).unwrap(), TEACHER);
    }

    #[test]
    fn the_mixture_applies_the_teacher_about_beta_of_the_time_and_repeats_for_a_seed() {
        let run = |seed| {
            let mut d = dagger(0.3);
            d.reset(seed).unwrap();
            (0..2000)
                .map(|_| d.act(&obs()).unwrap() == TEACHER)
                .collect::<Vec<_>>()
        };
        let a = run(7);
        let share = a.iter().filter(|&&t| t).count() as f64 / a.len() as f64;
        assert!(
            (share - 0.3).abs() < 0.04,
            "teacher applied {share} of the time"
        );
        assert_eq!(a, run(7), "the same seed, the same decisions");
        assert_ne!(a, run(8));
    }

    #[test]
    fn a_share_outside_0_1_is_refused() {
        for beta in [-0.1, 1.5, f64::NAN] {
            let err = dagger(beta).reset(1).expect_err("refused");
            assert!(err.to_string().contains("must be in [0, 1]"), "{err}");
        }
    }
}
