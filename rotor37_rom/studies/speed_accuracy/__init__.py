"""The speed-accuracy study (issue #22): per scene, the cost and the error of every candidate model against a
reference, written to the study file ``rotor37_rom/data/speed_accuracy.json`` that ``studies.model_choice.choose_model``
reads. ``benchmarks/speed_accuracy.py`` is its command line (the scenes' settings are in its docstring).

Modules, one per scene family:

- ``context``: the settings the scenes share and ``StudyContext`` (the folders of a run, what it computed);
- ``study_file``: the study file's schema (the scene records) and its reader and writer;
- ``blade_statics``: ``modes`` and ``clearance``; ``maps``: one interaction map of a scene, cached, and the held-out
  loop; ``blade_maps``: ``map-*`` and ``history-*``; ``blade_stress``: ``stress-*`` and ``stability``;
- ``disk_modes``: ``disk-modes``; ``disk_maps``: ``disk-map-*``; ``disk_stress``: ``disk-stress-*``;
  ``disk_forced``: ``disk-forced-*``;
- ``cost``: ``cost-r`` and ``paper-speedup`` (synthetic models timed per simulation-step);
- ``charts`` and ``docs``: the charts in docs/img and the generated block of docs/choosing-a-model.md;
- ``scenes``: the registry of scenes and ``run_study``.

Nothing is imported here: ``model_choice`` reads the file through ``study_file`` without the scenes.
"""
