"""Demo scenes and the script that renders them (`make demo`).

The demos are tracer scenes built in code (`scenes`, `metamers`), rendered by `run_demos` and
measured by `metrics`; `display` makes the pictures. Turning them into .blend files that render
through the add-on (issue 6) is a later step that should reproduce the settings in `scenes`.
"""
