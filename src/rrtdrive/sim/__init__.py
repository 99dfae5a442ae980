"""highway-env glue: the ego car, scenes, map extraction, the closed-loop runner, video."""
