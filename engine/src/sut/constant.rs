use super::{Sut, SutError};
use crate::{Control, Observation};

/// Open-loop control: the same [`Control`] at every step, blind to the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantControl(pub Control);

impl Sut for ConstantControl {
    fn reset(&mut self, _seed: u64) -> Result<(), SutError> {
        Ok(())
    }

    fn act(&mut self, _obs: &Observation<'_>) -> Result<Control, SutError> {
        Ok(self.0)
    }
}
