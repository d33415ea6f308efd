//! An error and its causes as one line of text: `message: cause: cause…`.
//!
//! The crates' errors keep their cause as `Error::source()` and do not print it, so that a program
//! walking the chain meets each cause once; where an error becomes text for a person (the command
//! line's messages and JSON documents, the Python exceptions, the notes and reports that quote an
//! error) the text is rendered here, once, from the chain.

extern crate alloc;
use alloc::string::{String, ToString};
use core::error::Error;
use core::fmt;

/// Displays an error followed by each of its causes, separated by `": "`.
///
/// A cause whose text the previous link's message already ends with is not written again: some
/// foreign errors (serde_json's I/O errors, for one) print their cause and also return it, and the
/// chain says each cause once.
#[derive(Clone, Copy)]
pub struct Chain<'a>(pub &'a (dyn Error + 'a));

impl fmt::Display for Chain<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut shown: String = self.0.to_string();
        f.write_str(&shown)?;
        let mut cause = self.0.source();
        while let Some(e) = cause {
            let text = e.to_string();
            if !shown.ends_with(&text) {
                write!(f, ": {text}")?;
            }
            shown = text;
            cause = e.source();
        }
        Ok(())
    }
}

impl fmt::Debug for Chain<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use super::Chain;
    use std::error::Error;
    use std::fmt;

    /// An error with a message and an optional cause it does not print.
    #[derive(Debug)]
    struct Link(&'static str, Option<Box<dyn Error + Send + Sync>>);

    impl fmt::Display for Link {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str(self.0)
        }
    }

    impl Error for Link {
        fn source(&self) -> Option<&(dyn Error + 'static)> {
            self.1.as_deref().map(|e| e as &(dyn Error + 'static))
        }
    }

    #[test]
    fn an_error_without_cause_is_its_message() {
        assert_eq!(Chain(&Link("alone", None)).to_string(), "alone");
    }

    #[test]
    fn each_cause_follows_after_a_colon() {
        let inner = Link("innermost", None);
        let middle = Link("middle", Some(Box::new(inner)));
        let outer = Link("outer", Some(Box::new(middle)));
        assert_eq!(Chain(&outer).to_string(), "outer: middle: innermost");
    }

    /// An error in the old style: it prints its cause and also returns it.
    #[derive(Debug)]
    struct Prints(Link);

    impl fmt::Display for Prints {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "cannot parse: {}", self.0)
        }
    }

    impl Error for Prints {
        fn source(&self) -> Option<&(dyn Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn a_cause_its_parent_already_prints_is_said_once() {
        let foreign = Prints(Link("line 3", Some(Box::new(Link("not a number", None)))));
        let outer = Link("plan.toml", Some(Box::new(foreign)));
        assert_eq!(
            Chain(&outer).to_string(),
            "plan.toml: cannot parse: line 3: not a number"
        );
    }

    #[test]
    fn serde_json_and_io_errors_say_each_cause_once() {
        // serde_json's I/O error prints the io::Error and hands over its source; an io::Error
        // around an error prints that error and hands over the error's source.
        let inner = Link("bad frame", Some(Box::new(Link("crc mismatch", None))));
        let json = serde_json::Error::io(std::io::Error::other(inner));
        assert_eq!(json.to_string(), "bad frame");
        let outer = Link("cannot write summary as JSON", Some(Box::new(json)));
        assert_eq!(
            Chain(&outer).to_string(),
            "cannot write summary as JSON: bad frame: crc mismatch"
        );
    }

    #[test]
    fn an_io_error_around_an_error_says_it_once() {
        // io::Error's custom errors print the inner error and return the inner error's source.
        let inner = Link("bad frame", Some(Box::new(Link("crc mismatch", None))));
        let io = std::io::Error::other(inner);
        let outer = Link("cannot read log", Some(Box::new(io)));
        assert_eq!(
            Chain(&outer).to_string(),
            "cannot read log: bad frame: crc mismatch"
        );
    }
}
