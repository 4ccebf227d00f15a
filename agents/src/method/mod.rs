//! What every method declares, and the agent that runs any of them.

pub mod agent;
