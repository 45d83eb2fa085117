"""The exponential (paper-form) surrogate: angle = A (exp(x + c x^2) - 1), x = p / tau,
A = a L, tau = a_t log10(b_t t), fitted per family from the FE curve database.

Modules, each one idea:

    equations        the model's equations, their inverse and gradients (the only copy)
    parameters       one family's parameter set of one form, covariance, JSON form
    bands            every band of the model: scatter model, angle_band, pressure_band
    per_curve_fits   per-curve fits of A and tau (the paper's Tables 4-5 first stage)
    paper_procedure  the paper's two-stage procedure on one family (report only)
    family_fit       joint fit of one family's curves and its leave-one-design-out check
    family           a fitted family: its designs, parameters per form, domain
    validity         validity flags and the FE's range for a family
    surrogate        ``Surrogate``: predict / inverse with bands (implements Predictor)
    fit_from_curves  ``fit_surrogate``: every family of a curve database
    file             versioned JSON files (save / load / open)
    paper_tables     the paper's published constants and tables
    paper_preset     the ``paper`` preset built from them
    inverse_design   which (pair, L, t) meets a target
    synthetic_curves synthetic curves that follow the model (tests, benchmarks)
    report_plots     the fit report's PNGs
"""
