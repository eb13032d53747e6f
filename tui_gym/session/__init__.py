"""The composition root, above games and algorithms: a session (game × algorithm × wrappers ×
seed), its runners, human play and the game protocol, saving agents, recording, experiments
and the arena."""
