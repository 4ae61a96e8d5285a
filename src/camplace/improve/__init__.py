"""camplace.improve (layer 9): beyond the candidate grid - refine (each camera moved off the
grid by a compass search) and adaptive (rounds of finer candidates); both raycast new poses
through the engine that computed V (``Visibility.engine``) and append them to V; people
(a swap descent of a crowd-aware placement that counts the people seen by Γ^p cameras, issue 36)."""
