//! The checks of a description's values: [`ParamError`], the error that names the source,
//! the field at fault and its valid range, and `Checker`, which builds it for one source.
//! Every description (a device file, its interface circuit's keys) checks its values with
//! these, so that each error reads alike.

use thiserror::Error;

/// A parameter that failed to load or validate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ParamError {
    /// The text is not valid TOML for a device, or has unknown keys.
    #[error("{source_name}: {message}")]
    Parse {
        /// Where the text came from (a file name).
        source_name: String,
        /// The TOML parser's message.
        message: String,
    },
    /// A field is outside its valid range.
    #[error("{source_name}: field `{field}` = {value:e} is out of range: must be {range}")]
    OutOfRange {
        /// Where the text came from (a file name).
        source_name: String,
        /// Dotted path of the field, e.g. `mechanics.mass_kg`.
        field: String,
        /// The offending value.
        value: f64,
        /// Human-readable valid range.
        range: String,
    },
    /// A required field is absent.
    #[error("{source_name}: field `{field}` is missing: {what}")]
    Missing {
        /// Where the text came from (a file name).
        source_name: String,
        /// Dotted path of the field.
        field: String,
        /// What the field is, or what needs it.
        what: String,
    },
    /// A field is present where it does not belong, or fields contradict each other.
    #[error("{source_name}: field `{field}`: {message}")]
    Invalid {
        /// Where the text came from (a file name).
        source_name: String,
        /// Dotted path of the field.
        field: String,
        /// What is wrong.
        message: String,
    },
}

impl ParamError {
    /// The dotted path of the field at fault, where the error names one.
    pub fn field(&self) -> Option<&str> {
        match self {
            ParamError::Parse { .. } => None,
            ParamError::OutOfRange { field, .. }
            | ParamError::Missing { field, .. }
            | ParamError::Invalid { field, .. } => Some(field),
        }
    }
}

/// Builds [`ParamError`]s that name the source and check ranges.
pub(crate) struct Checker<'a> {
    pub(crate) source: &'a str,
}

impl Checker<'_> {
    pub(crate) fn err(&self, field: &str, value: f64, range: &str) -> ParamError {
        ParamError::OutOfRange {
            source_name: self.source.to_string(),
            field: field.to_string(),
            value,
            range: range.to_string(),
        }
    }
    pub(crate) fn missing(&self, field: &str, what: &str) -> ParamError {
        ParamError::Missing {
            source_name: self.source.to_string(),
            field: field.to_string(),
            what: what.to_string(),
        }
    }
    pub(crate) fn message(&self, field: &str, message: &str) -> ParamError {
        ParamError::Invalid {
            source_name: self.source.to_string(),
            field: field.to_string(),
            message: message.to_string(),
        }
    }
    pub(crate) fn positive(&self, field: &str, v: f64) -> Result<(), ParamError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.err(field, v, "finite and > 0"))
        }
    }
    pub(crate) fn non_negative(&self, field: &str, v: f64) -> Result<(), ParamError> {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(self.err(field, v, "finite and >= 0"))
        }
    }
    pub(crate) fn within(
        &self,
        field: &str,
        v: f64,
        lo: f64,
        hi: f64,
        range: &str,
    ) -> Result<(), ParamError> {
        if v.is_finite() && v > lo && v < hi {
            Ok(())
        } else {
            Err(self.err(field, v, range))
        }
    }
    pub(crate) fn within_closed(
        &self,
        field: &str,
        v: f64,
        lo: f64,
        hi: f64,
        range: &str,
    ) -> Result<(), ParamError> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(())
        } else {
            Err(self.err(field, v, range))
        }
    }
}
