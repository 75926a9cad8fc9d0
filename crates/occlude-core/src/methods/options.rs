//! Method parameters: typed ([`MethodParams`], each with its defaults) and
//! from the command line (`--method-opt chc.tav=2`, [`MethodOptions`]). Each
//! method describes its parameters once, with their valid ranges, so that a
//! bad value is an error naming the parameter and the range, whether it came
//! as a string or was set in Rust, and an unknown key is never ignored.

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

    /// A visitor reading one method's parameters from these options.
    pub fn for_method(&self, method: &str) -> ParamVisitor {
        let given =
            self.entries.iter().filter(|((m, _), _)| m == method).map(|((_, k), v)| (k.clone(), v.clone())).collect();
        ParamVisitor { method: method.to_string(), given: Some(given), known: Vec::new(), seen: Vec::new() }
    }
}

/// One method's parameters as a Rust type with its defaults
/// ([`Default`]). [`MethodParams::visit`] names each parameter once, with
/// its key, its field and its valid range; that one description reads the
/// command line's strings, checks values a program set, and lists the
/// values for the report.
pub trait MethodParams: Clone + Default {
    /// The method whose parameters these are (the `chc` of `chc.tav`).
    const METHOD: &'static str;

    /// Visits every parameter in a fixed order (see [`ParamVisitor`]).
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError>;

    /// The defaults with `options`' values for this method put in; a key
    /// the method does not have, or a value out of range, is an error.
    fn from_options(options: &MethodOptions) -> Result<Self, OptionError> {
        let mut params = Self::default();
        read_params(Self::METHOD, options, |v| params.visit(v))?;
        Ok(params)
    }

    /// Fails on the first value out of its range, named as on the command
    /// line.
    fn check(&self) -> Result<(), OptionError> {
        self.values().map(drop)
    }

    /// `(key, value)` pairs in visiting order, each value as the command
    /// line writes it; an error for a value out of its range.
    fn values(&self) -> Result<Vec<(String, String)>, OptionError> {
        list_params(Self::METHOD, |v| self.clone().visit(v))
    }
}

/// Reads `method`'s values of `options` into the fields `visit` visits; a
/// key it does not visit, or a value out of range, is an error.
pub(crate) fn read_params(
    method: &str,
    options: &MethodOptions,
    visit: impl FnOnce(&mut ParamVisitor) -> Result<(), OptionError>,
) -> Result<(), OptionError> {
    let mut v = options.for_method(method);
    visit(&mut v)?;
    v.finish().map(drop)
}

/// The `(key, value)` pairs of the fields `visit` visits for `method`,
/// each checked against its range.
pub(crate) fn list_params(
    method: &str,
    visit: impl FnOnce(&mut ParamVisitor) -> Result<(), OptionError>,
) -> Result<Vec<(String, String)>, OptionError> {
    let mut v = ParamVisitor::checking(method);
    visit(&mut v)?;
    v.finish()
}

/// Walks one method's parameters ([`MethodParams::visit`]): reading the
/// command line's values into the fields, or checking the fields as set.
/// Either way it collects each value for the report.
#[derive(Debug)]
pub struct ParamVisitor {
    method: String,
    /// The command line's values not yet read; `None` when checking.
    given: Option<BTreeMap<String, String>>,
    known: Vec<&'static str>,
    seen: Vec<(String, String)>,
}

impl ParamVisitor {
    /// A visitor that checks the fields as they stand.
    fn checking(method: &str) -> Self {
        Self { method: method.to_string(), given: None, known: Vec::new(), seen: Vec::new() }
    }

    /// The parameter `key` held in `field`, described by `expected` in an
    /// error, valid where `valid` says so. A value given for `key` on the
    /// command line replaces the field.
    pub fn value<T: FromStr + Display>(
        &mut self,
        key: &'static str,
        field: &mut T,
        expected: &str,
        valid: impl Fn(&T) -> bool,
    ) -> Result<(), OptionError> {
        self.visit(key, field, expected, |text| text.parse().ok(), valid)
    }

    /// A boolean switch (`true`/`false`, `on`/`off`, `1`/`0`).
    pub fn flag(&mut self, key: &'static str, field: &mut bool) -> Result<(), OptionError> {
        let parse = |text: &str| match text {
            "true" | "on" | "1" => Some(true),
            "false" | "off" | "0" => Some(false),
            _ => None,
        };
        self.visit(key, field, "true or false", parse, |_| true)
    }

    /// Whether the user gave `key` (before it is visited), or, when
    /// checking, always: an error about two parameters then names the one
    /// the user set, not a default.
    pub fn is_set(&self, key: &str) -> bool {
        self.given.as_ref().is_none_or(|given| given.contains_key(key))
    }

    /// An error about `key`'s `value`.
    pub fn bad_value(&self, key: &str, value: impl Display, expected: impl Into<String>) -> OptionError {
        OptionError::BadValue {
            method: self.method.clone(),
            key: key.to_string(),
            value: value.to_string(),
            expected: expected.into(),
        }
    }

    fn visit<T: Display>(
        &mut self,
        key: &'static str,
        field: &mut T,
        expected: &str,
        parse: impl Fn(&str) -> Option<T>,
        valid: impl Fn(&T) -> bool,
    ) -> Result<(), OptionError> {
        self.known.push(key);
        match self.given.as_mut().and_then(|given| given.remove(key)) {
            Some(text) => match parse(&text) {
                Some(v) if valid(&v) => *field = v,
                _ => return Err(self.bad_value(key, text, expected)),
            },
            None if !valid(field) => return Err(self.bad_value(key, &*field, expected)),
            None => {}
        }
        self.seen.push((key.to_string(), field.to_string()));
        Ok(())
    }

    /// Ends the walk: fails on a key the method did not visit; returns the
    /// values in use (defaults included) for the report.
    pub fn finish(self) -> Result<Vec<(String, String)>, OptionError> {
        if let Some(key) = self.given.and_then(|given| given.into_keys().next()) {
            let known = if self.known.is_empty() {
                " (it takes no parameters)".to_string()
            } else {
                format!(" (its parameters: {})", self.known.join(", "))
            };
            return Err(OptionError::UnknownKey { method: self.method, key, known });
        }
        Ok(self.seen)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parameters of a method made up for the tests.
    #[derive(Clone, Debug, PartialEq)]
    struct Demo {
        tav: u32,
        smax: f32,
        tight: bool,
    }

    impl Default for Demo {
        fn default() -> Self {
            Self { tav: 0, smax: 1.4, tight: true }
        }
    }

    impl MethodParams for Demo {
        const METHOD: &'static str = "demo";
        fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
            v.value("tav", &mut self.tav, "an integer from 0 to 10", |&t| t <= 10)?;
            v.value("smax", &mut self.smax, "a number >= 1", |&s| s >= 1.0)?;
            v.flag("tight", &mut self.tight)
        }
    }

    fn read(items: &[&str]) -> Result<Demo, OptionError> {
        Demo::from_options(&MethodOptions::parse(items).unwrap())
    }

    #[test]
    fn strings_fill_the_typed_parameters_over_their_defaults() {
        assert_eq!(read(&[]), Ok(Demo::default()));
        assert_eq!(read(&["demo.tav=2", "demo.tight = off"]), Ok(Demo { tav: 2, smax: 1.4, tight: false }));
        assert_eq!(read(&["other.tav=2"]), Ok(Demo::default()));
        let err = read(&["demo.smax=0.5"]).unwrap_err().to_string();
        assert!(err.contains("demo.smax = 0.5: expected a number >= 1"), "{err}");
        let err = read(&["demo.tight=maybe"]).unwrap_err().to_string();
        assert!(err.contains("expected true or false"), "{err}");
        let err = read(&["demo.zzz=1"]).unwrap_err().to_string();
        assert!(err.contains("no parameter 'zzz' (its parameters: tav, smax, tight)"), "{err}");
    }

    #[test]
    fn typed_values_are_checked_and_listed_as_the_command_line_writes_them() {
        let params = Demo { tav: 3, smax: 2.5, tight: false };
        assert_eq!(params.check(), Ok(()));
        let listed = params.values().unwrap();
        assert_eq!(listed, [("tav", "3"), ("smax", "2.5"), ("tight", "false")].map(|(k, v)| (k.into(), v.into())));
        let items: Vec<String> = listed.iter().map(|(k, v)| format!("demo.{k}={v}")).collect();
        assert_eq!(Demo::from_options(&MethodOptions::parse(&items).unwrap()), Ok(params));
        let err = Demo { tav: 11, ..Demo::default() }.check().unwrap_err().to_string();
        assert!(err.contains("demo.tav = 11: expected an integer from 0 to 10"), "{err}");
    }

    #[test]
    fn malformed_repeated_and_stray_options_are_errors() {
        assert!(matches!(MethodOptions::parse(&["tav=2"]), Err(OptionError::Malformed(_))));
        assert!(matches!(MethodOptions::parse(&["chc.tav"]), Err(OptionError::Malformed(_))));
        assert!(matches!(MethodOptions::parse(&["chc.tav=1", "chc.tav=2"]), Err(OptionError::Repeated(_))));
        let opts = MethodOptions::parse(&["chc.tav=1"]).unwrap();
        assert!(opts.check_methods(&["vfc".to_string()]).is_err());
        assert!(opts.check_methods(&["chc".to_string()]).is_ok());
        let err = MethodOptions::parse(&["vfc.x=1"]).unwrap().for_method("vfc").finish().unwrap_err();
        assert!(err.to_string().contains("(it takes no parameters)"), "{err}");
    }
}
