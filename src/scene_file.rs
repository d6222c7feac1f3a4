//! Scene files (TOML). Unknown keys are errors; every error is one line that
//! names the file, the place and what is wrong.

use std::path::Path;

use thiserror::Error;

use crate::scene::{Scene, SceneError};

/// A scene file that cannot be used.
#[derive(Debug, Error)]
pub enum SceneFileError {
    #[error("cannot read scene file {path}: {reason}")]
    Read { path: String, reason: String },
    #[error("scene file {path}, line {line}, column {column}: {message}")]
    Parse {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("scene file {path}: {source}")]
    Invalid {
        path: String,
        #[source]
        source: SceneError,
    },
}

/// Reads, parses and validates a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneFileError> {
    let shown = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| SceneFileError::Read {
        path: shown.clone(),
        reason: e.to_string(),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| SceneFileError::Read {
        path: shown.clone(),
        reason: format!(
            "it is not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ),
    })?;
    let scene = parse(&text).map_err(|(line, column, message)| SceneFileError::Parse {
        path: shown.clone(),
        line,
        column,
        message,
    })?;
    scene.validate().map_err(|source| SceneFileError::Invalid {
        path: shown,
        source,
    })?;
    Ok(scene)
}

/// Parses scene text; on error gives (line, column, one-line message).
pub fn parse(text: &str) -> Result<Scene, (usize, usize, String)> {
    toml::from_str::<Scene>(text).map_err(|e| {
        let offset = e.span().map(|s| s.start).unwrap_or(0).min(text.len());
        let before = &text[..floor_char_boundary(text, offset)];
        let line = before.matches('\n').count() + 1;
        let column = before
            .rsplit('\n')
            .next()
            .map(|l| l.chars().count())
            .unwrap_or(0)
            + 1;
        let message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
        (line, column, message)
    })
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}
