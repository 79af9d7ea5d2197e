//! weft's errors as Python exceptions, with the whole chain of causes in the message
//! (`file: field: what was expected`).

use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::PyErr;

/// `e` and its sources joined with ": ".
fn chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let part = s.to_string();
        if !text.contains(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        source = s.source();
    }
    text
}

/// A `ValueError` carrying weft's message.
pub fn value_error(e: impl std::error::Error + 'static) -> PyErr {
    PyValueError::new_err(chain(&e))
}

/// An `OSError` carrying weft's message (reading or writing files).
pub fn os_error(e: impl std::error::Error + 'static) -> PyErr {
    PyOSError::new_err(chain(&e))
}

/// A `ValueError` with a message written here.
pub fn invalid(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
