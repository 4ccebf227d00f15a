//! Stopping and certifying: the stop rules ([`stopping`]), the decentralized certified
//! stop ([`local_stop`]), rounding and repair ([`rounding`]), and the centralized optimum
//! every certificate is checked against ([`oracle`]).

pub mod local_stop;
pub mod oracle;
pub mod rounding;
pub mod stopping;
