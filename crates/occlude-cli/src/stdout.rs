//! Printing a command's table to standard output, after its files are
//! written: a reader that has gone away (`occlude bench | head -1`, a closed
//! pipe) ends the printing quietly, and a standard output that cannot be
//! written (a full disk) is an error, never a panic as `print!` gives.

use std::io::{ErrorKind, Write};

/// Writes `text` to standard output. A closed pipe is not an error: the
/// reader took what it wanted, and the command's files are already written.
pub fn print(text: &str) -> anyhow::Result<()> {
    write_to(&mut std::io::stdout().lock(), text)
}

/// Writes `text` to `out` as [`print`] does.
fn write_to(out: &mut dyn Write, text: &str) -> anyhow::Result<()> {
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != ErrorKind::BrokenPipe => {
            Err(anyhow::Error::new(e).context("cannot write to standard output"))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Failing(ErrorKind);

    impl Write for Failing {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(self.0.into())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_closed_pipe_ends_quietly_and_other_failures_are_errors() {
        write_to(&mut Failing(ErrorKind::BrokenPipe), "table").unwrap();
        let e = write_to(&mut Failing(ErrorKind::StorageFull), "table").unwrap_err();
        assert!(format!("{e:#}").contains("cannot write to standard output"), "{e:#}");
        let mut written = Vec::new();
        write_to(&mut written, "table").unwrap();
        assert_eq!(written, b"table");
    }
}
