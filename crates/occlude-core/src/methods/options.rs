//! Method parameters from the command line (`--method-opt chc.tav=2`), read
//! by each method with its valid range, so that a bad value is an error naming
//! the parameter and the range, and an unknown key is never silently ignored.

use std::collections::BTreeMap;
use std::fmt::Display;
use std::str::FromStr;
use thiserror::Error;

/// A problem with a method parameter.
#[derive(Debug, Error, PartialEq)]
pub enum OptionError {
    /// Not of the form `method.key=value`.
    #[error("method option '{0}' is not of the form method.key=value (e.g. chc.tav=2)")]
    Malformed(String),
    /// The same key given twice.
    #[error("method option '{0}' is given twice")]
    Repeated(String),
    /// The method has no such parameter.
    #[error("method '{method}' has no parameter '{key}'{known}")]
    UnknownKey {
        /// Method name.
        method: String,
        /// The unknown key.
        key: String,
        /// The method's parameters, listed for the message.
        known: String,
    },
    /// An option names a method that is not being run.
    #[error("method option '{0}' is for a method that is not in --methods")]
    UnusedMethod(String),
    /// The value does not parse or is out of range.
    #[error("{method}.{key} = {value}: expected {expected}")]
    BadValue {
        /// Method name.
        method: String,
        /// Parameter name.
        key: String,
        /// The value given.
        value: String,
        /// The valid type and range.
        expected: String,
    },
}

/// All `method.key=value` options of a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MethodOptions {
    entries: BTreeMap<(String, String), String>,
}

impl MethodOptions {
    /// Parses `method.key=value` strings.
    pub fn parse<S: AsRef<str>>(items: &[S]) -> Result<Self, OptionError> {
        let mut entries = BTreeMap::new();
        for item in items {
            let item = item.as_ref().trim();
            let malformed = || OptionError::Malformed(item.to_string());
            let (name, value) = item.split_once('=').ok_or_else(malformed)?;
            let (method, key) = name.split_once('.').ok_or_else(malformed)?;
            let (method, key, value) = (method.trim(), key.trim(), value.trim());
            if method.is_empty() || key.is_empty() || value.is_empty() {
                return Err(malformed());
            }
            if entries.insert((method.to_string(), key.to_string()), value.to_string()).is_some() {
                return Err(OptionError::Repeated(name.to_string()));
            }
        }
        Ok(Self { entries })
    }

    /// Fails when an option names a method outside `methods`.
    pub fn check_methods(&self, methods: &[String]) -> Result<(), OptionError> {
        match self.entries.keys().find(|(m, _)| !methods.contains(m)) {
            Some((m, k)) => Err(OptionError::UnusedMethod(format!("{m}.{k}"))),
            None => Ok(()),
        }
    }

    /// The reader for one method's parameters.
    pub fn for_method(&self, method: &str) -> OptionReader {
        let values =
            self.entries.iter().filter(|((m, _), _)| m == method).map(|((_, k), v)| (k.clone(), v.clone())).collect();
        OptionReader { method: method.to_string(), values, known: Vec::new(), chosen: Vec::new() }
    }
}

/// Reads one method's parameters, each with a default and a valid range.
#[derive(Debug)]
pub struct OptionReader {
    method: String,
    values: BTreeMap<String, String>,
    known: Vec<&'static str>,
    chosen: Vec<(String, String)>,
}

impl OptionReader {
    /// The value of `key` (or `default`), which must parse as `T` and
    /// satisfy `valid`, described by `expected` in the error.
    pub fn get<T: FromStr + Display + Copy>(
        &mut self,
        key: &'static str,
        default: T,
        expected: &str,
        valid: impl Fn(T) -> bool,
    ) -> Result<T, OptionError> {
        self.known.push(key);
        let value = match self.values.remove(key) {
            None => default,
            Some(text) => match text.parse::<T>() {
                Ok(v) if valid(v) => v,
                _ => {
                    return Err(OptionError::BadValue {
                        method: self.method.clone(),
                        key: key.to_string(),
                        value: text,
                        expected: expected.to_string(),
                    })
                }
            },
        };
        self.chosen.push((key.to_string(), value.to_string()));
        Ok(value)
    }

    /// Whether the user gave `key` (before it is read): an error about two
    /// parameters then names the one the user set, not a default.
    pub fn is_set(&self, key: &str) -> bool {
        self.values.contains_key(key)
    }

    /// A boolean switch (`true`/`false`, `on`/`off`, `1`/`0`).
    pub fn flag(&mut self, key: &'static str, default: bool) -> Result<bool, OptionError> {
        self.known.push(key);
        let value = match self.values.remove(key) {
            None => default,
            Some(text) => match text.as_str() {
                "true" | "on" | "1" => true,
                "false" | "off" | "0" => false,
                _ => {
                    return Err(OptionError::BadValue {
                        method: self.method.clone(),
                        key: key.to_string(),
                        value: text,
                        expected: "true or false".to_string(),
                    })
                }
            },
        };
        self.chosen.push((key.to_string(), value.to_string()));
        Ok(value)
    }

    /// Ends reading: fails on a key the method did not ask for; returns the
    /// values in use (defaults included) for the report.
    pub fn finish(self) -> Result<Vec<(String, String)>, OptionError> {
        if let Some(key) = self.values.into_keys().next() {
            let known = if self.known.is_empty() {
                " (it takes no parameters)".to_string()
            } else {
                format!(" (its parameters: {})", self.known.join(", "))
            };
            return Err(OptionError::UnknownKey { method: self.method, key, known });
        }
        Ok(self.chosen)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_values_defaults_and_rejects_bad_ones() {
        let opts = MethodOptions::parse(&["chc.tav=2", "chc.nvp = 25"]).unwrap();
        let mut r = opts.for_method("chc");
        assert_eq!(r.get("tav", 0u32, "an integer >= 0", |_| true), Ok(2));
        assert_eq!(r.get("nvp", 0u32, "an integer >= 0", |_| true), Ok(25));
        assert_eq!(r.get("b", 50u32, "an integer >= 1", |v| v >= 1), Ok(50));
        assert_eq!(r.finish().unwrap().len(), 3);

        let opts = MethodOptions::parse(&["chcpp.smax=0.5", "chcpp.zzz=1"]).unwrap();
        let mut r = opts.for_method("chcpp");
        let err = r.get("smax", 1.4f32, "a number >= 1", |v| v >= 1.0).unwrap_err();
        assert!(err.to_string().contains("chcpp.smax = 0.5: expected a number >= 1"), "{err}");
        let mut r = opts.for_method("chcpp");
        r.get("smax", 1.4f32, "any number", |_| true).unwrap();
        r.flag("tight", true).unwrap();
        assert!(r.finish().unwrap_err().to_string().contains("no parameter 'zzz'"));
    }

    #[test]
    fn malformed_repeated_and_stray_options_are_errors() {
        assert!(matches!(MethodOptions::parse(&["tav=2"]), Err(OptionError::Malformed(_))));
        assert!(matches!(MethodOptions::parse(&["chc.tav"]), Err(OptionError::Malformed(_))));
        assert!(matches!(MethodOptions::parse(&["chc.tav=1", "chc.tav=2"]), Err(OptionError::Repeated(_))));
        let opts = MethodOptions::parse(&["chc.tav=1"]).unwrap();
        assert!(opts.check_methods(&["vfc".to_string()]).is_err());
        assert!(opts.check_methods(&["chc".to_string()]).is_ok());
        let mut r = MethodOptions::parse(&["vfc.x=1"]).unwrap().for_method("vfc");
        assert!(r.flag("y", false).is_ok());
    }
}
