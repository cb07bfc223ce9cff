"""Physical constants used everywhere (SI units)."""

#: Acceleration of gravity [m/s^2]. Used by every backend and by the dimensionless axes
#: a_g / (g tan alpha). Record files in units of g are converted with :data:`G_STANDARD`.
G = 9.81

#: Standard gravity [m/s^2], used only to convert accelerograms given in units of g
#: (PEER AT2 files), so that PGAs match the values the data providers publish.
G_STANDARD = 9.80665

#: Free rocking [s] simulated after the ground motion ends (or from the initial tilt of a
#: free-rocking run) when no duration is given: the default run length of every backend and
#: path is the motion's length + FREE_TAIL.
FREE_TAIL = 10.0

#: Free rocking [s] added to an analytic run that ended, after the ground motion, past its
#: critical angle and not yet fallen, so that a fall under way is finished: the engines' verdict
#: rule (a structure past its critical angle when the ground motion is over falls) decided by
#: the reference model itself. A frame just past its critical angle leaves it at the rate p
#: (about 1-2 1/s for the paper's frames): 20 s covers a start 1e-9 rad beyond it.
FALL_EXTENSION = 20.0

#: The one ladder of engine time steps [s], coarse to fine: what a work-precision sweep
#: (``rockbench tradeoff``), a search (``rockbench advise``, the report) and a precision curve
#: of dt run by default (:func:`rockbench.studies.tradeoff.settings_grid`,
#: :func:`rockbench.studies.advise.precision_knob`).
DT_LADDER: tuple[float, ...] = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4)

#: The default CPU budget [s] of the decision's search (rockbench.studies.search) per
#: evidence size (None: no limit): process CPU of the search and its workers, builds, warm-ups
#: and pools included. Beyond it the answer says what to run next and what it would cost. The quick one leaves a quick report (the search and
#: the rest of the page) within 2 CPU minutes on 2 cores.
BUDGETS: dict[str, float | None] = {"quick": 60.0, "default": 600.0, "full": None}
