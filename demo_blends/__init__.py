"""Demo scenes: the .blend files, the script that builds them and the one that renders them (`make demo`).

`scenes` and `metamers` hold every number as tracer scenes built in code; `build_blends` (with the
add-on's importer parts and `blend_parts`) writes them as .blend files with the add-on's settings;
`run_demos` renders those files through the add-on and `metrics` measures the films; `display` makes
the pictures.
"""
