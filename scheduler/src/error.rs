//! What stops a run before the front reaches the end time.

/// What stopped a run before the front reached the end time.
#[derive(Debug, thiserror::Error)]
pub enum RunError<E> {
    /// No vertex below the end time can be pitched: the pitching rule lost progress.
    #[error("no progress: {remaining} vertices are below the end time but none can be pitched")]
    Stalled {
        /// Vertices not yet at the end time.
        remaining: usize,
    },
    /// A tent or a record failed.
    #[error(transparent)]
    Work(E),
    /// A tent, a record or an event panicked: a bug. The run ends in every mode, with the
    /// panic's message, instead of leaving the other threads waiting.
    #[error("internal error (a bug, please report it): {0}")]
    Panic(String),
}

/// The message of a caught panic.
pub(crate) fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}
