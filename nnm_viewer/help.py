"""The Help tab: a short explanation of what the viewer shows, for students and engineers."""

HELP_MARKDOWN = """\
**Frequency-energy plot (FEP).** Every point is a *nonlinear normal mode* (NNM) motion: a periodic
orbit of the undamped structure, in which all DOFs move with one period. The x axis is the orbit's
total energy (J, log scale), the y axis its frequency (Hz, 1/period). At low energy a branch starts
at the frequency of its linear mode; hardening springs raise the frequency with energy, softening
ones lower it. The *relative* axis option shows f / f_linear − 1 (%) instead, so that branches of
very different frequencies can be read together. The branches are computed by continuation
(shooting and pseudo-arclength): one point after the other, along the branch.

**Floquet multipliers, stability.** Perturb an orbit slightly and follow it for one period: the
perturbation is multiplied by the *monodromy matrix*, whose eigenvalues are the Floquet multipliers
μ. In an undamped structure they come in pairs (μ, 1/μ), and one pair is always 1, 1 (shifting the
orbit in time, or moving to the next orbit of the branch). An orbit is **stable** when every |μ| ≤ 1
(up to a small tolerance), **unstable** when some |μ| > 1 (pale or hollow points). Where the
stability changes, a multiplier leaves the unit circle: through +1 (a **branch point** or a
**fold**, where the energy turns back), through −1 (a **period doubling**), or as a complex pair (a
**torus** bifurcation). These events are marked on both FEPs.

**Internal-resonance tongues.** When k times the branch's frequency meets the frequency of another
NNM family (k = 3, 5, … for odd springs such as cubic ones), the two interact: the branch leaves its
*backbone* and makes a narrow excursion, a **tongue**, where the orbit carries the other mode at k
times the frequency, then returns. On the FEP a tongue is a thin spike (often with folds and
unstable points); in the Point tab the k-th harmonic of some DOFs grows, up to exceeding the first.

**Point labels.** The solver labels every point: **backbone** (the fundamental NNM family) or
**tongue k:1** (inside the k:1 internal-resonance tongue), marked in orange on both FEPs (stars in the
panel, orange spheres on the board). By default a branch follows the tongues up to 3:1 and jumps
those of higher order (Tongues: follow-all follows every one); branches computed with tongue skipping
jump over all tongues and stay on the backbone. When the file has it, the Point tab also gives each
point's estimated relative frequency error (the accuracy of the orbit's frequency).

**Colours.** In the 3D view the colour of a vertex is its peak displacement over the period, from
blue (still) to red (the largest; see the colour bar). The motion is amplified so that it is
visible; the true peak displacement is printed under the animation controls.
"""
