"""Render jobs: one exported frame rendered by the renderer the Render settings choose, the same way for every
caller (F12, Render to Image, the command line).

- `protocol`: what every kind of job offers (`Job`), so a caller never asks which kind it holds: `start()` then
  `step()` on every UI timer tick until it is no longer `running` (a modal operator), or `run()` in the calling
  thread; `cancel()`; `fraction`, `message`, `warnings`, `describe()` while it renders; `result`, `error` and
  `succeeded` when it has ended. Where a kind cannot run, it says so (`engine_refusal`, `viewport_note`).
- `kinds`: the only place that reads the settings' `renderer` to choose a kind (`kind`, `render_job`).
- `tracer_job`: the tracer, on this computer or on the Dask farm (`TracerJob`, `render_tracer`). The Cycles
  emulation's kind is `cycles_emulation.job.EmulationJob`.

The Rendered viewport renders the tracer through its own restartable renderer (addon/engine/viewport_render.py),
with `render_tracer`, and asks `kinds` only for its note.
"""
