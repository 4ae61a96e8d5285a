"""camplace.improve (layer 9): beyond the candidate grid - refine (each camera moved off the
grid by a compass search), adaptive (rounds of finer candidates), relocate (each camera to the
best of a few other places, judged by their refined poses) and quality (these chained in one
time budget); all raycast new poses through the engine that computed V (``Visibility.engine``)
and append them to V; people (a swap descent of a crowd-aware placement that counts the people
seen by Γ^p cameras, issue 36)."""
