//! What every method declares, and the agent that runs any of them. The registry of the
//! methods themselves is [`crate::methods`].
//!
//! * [`info`]: a method's information ([`info::MethodInfo`]): name, role, stop rules,
//!   memory, certification, numbers, report text, the paper's figures;
//! * [`settings`]: a method's own settings type, one field and one spec per setting;
//! * [`team`]: how a method's team is built ([`team::TeamMethod`]) and what runners hold of
//!   it ([`team::MethodSetup`], [`team::TeamBuilder`]);
//! * [`agent`]: [`agent::MethodAgent`], any method's agent behind one dynamic call per step;
//! * [`masked`]: a method's agent on part of its team's robots and tasks (a standing team's
//!   episode), inside the team's fixed-size messages.

pub mod agent;
pub mod info;
pub mod masked;
pub mod settings;
pub mod team;
