//! Fitting a fabric's test data (Clyde et al. 2017 §5).
pub mod bootstrap;
pub mod optim;
