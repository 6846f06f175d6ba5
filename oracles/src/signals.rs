use std::borrow::Cow;

use thiserror::Error;

/// Errors reading a trace.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SignalError {
    /// A monitor needs a signal that the trace does not carry.
    #[error("signal `{0}` is missing from the trace")]
    Missing(String),
}

/// Named `f64` signals at one instant. Booleans are carried as `0.0` (false) and `1.0` (true).
///
/// A handful of signals per frame is the norm, so a flat list with linear look-up is both the
/// simplest and the fastest representation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Signals {
    values: Vec<(Cow<'static, str>, f64)>,
}

impl Signals {
    /// An empty set of signals.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets `name` to `value`, adding the signal if it is new.
    pub fn set(&mut self, name: &'static str, value: f64) {
        match self.values.iter_mut().find(|(n, _)| n == name) {
            Some(slot) => slot.1 = value,
            None => self.values.push((Cow::Borrowed(name), value)),
        }
    }

    /// Sets `name` to `value`, for a name made at run time (a signal a scenario publishes,
    /// `lead.speed`); the name is copied only when the signal is new.
    pub fn set_named(&mut self, name: &str, value: f64) {
        match self.values.iter_mut().find(|(n, _)| n == name) {
            Some(slot) => slot.1 = value,
            None => self.values.push((Cow::Owned(name.to_owned()), value)),
        }
    }

    /// Removes `name` (a stream with no value yet), if it is set.
    pub fn unset(&mut self, name: &str) {
        self.values.retain(|(n, _)| n != name);
    }

    /// Sets a boolean signal (`1.0` or `0.0`).
    pub fn set_bool(&mut self, name: &'static str, value: bool) {
        self.set(name, if value { 1.0 } else { 0.0 });
    }

    /// The value of `name`.
    ///
    /// # Errors
    /// [`SignalError::Missing`] if the signal was never set.
    pub fn get(&self, name: &str) -> Result<f64, SignalError> {
        self.values
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| SignalError::Missing(name.to_owned()))
    }

    /// The boolean value of `name`: true when the value is above `0.5`.
    ///
    /// # Errors
    /// [`SignalError::Missing`] if the signal was never set.
    pub fn get_bool(&self, name: &str) -> Result<bool, SignalError> {
        self.get(name).map(|v| v > 0.5)
    }

    /// `(name, value)` pairs in insertion order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, f64)> + '_ {
        self.values.iter().map(|(n, v)| (n.as_ref(), *v))
    }
}

/// One sample of a trace: the time since the start of the run and the signals at that time.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// Time since the start of the run, in seconds, `>= 0` and increasing from frame to frame.
    pub t_s: f64,
    /// The signals at `t_s`.
    pub signals: &'a Signals,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_overwrites_and_get_reports_missing_names() {
        let mut s = Signals::new();
        s.set("a", 1.0);
        s.set("a", 2.0);
        s.set_bool("b", true);
        assert_eq!(s.get("a"), Ok(2.0));
        assert_eq!(s.get_bool("b"), Ok(true));
        assert_eq!(s.get("c"), Err(SignalError::Missing("c".into())));
        assert_eq!(s.iter().count(), 2);
    }
}
