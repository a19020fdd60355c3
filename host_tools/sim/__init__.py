"""The plantation simulator: procedurally rendered trees and look-alikes seen by a downward JeVois camera.

- ``camera``: CameraModel (pinhole, nadir, JeVois-A33 sensor modes) and Pose; world <-> pixel.
- ``world``: World.from_map(pmap) renders the orthomosaic once; world.render(camera, pose) -> Frame with the
  ground truth of the trees (TreeInView) and objects (ObjectInView) in view; per-frame Effects.
- renderers: ``palms`` (oil palm, coconut, date palm), ``broadleaf`` (citrus, olive), ``objects`` (roof,
  road crossing), ``ground``; drawing and compositing in ``sprite``; ``crowns``: photo crowns from annotated
  aerial photos and a ground photo (``--crowns`` / ``--ground``, parsed once in ``cli_args``).
- ``clip``: the clip format (MJPG AVI + JSON sidecar), write_clip / read_clip; ``path``: flying the path F.
- ``dataset``: the crops and annotated frames of ``foranav synth``.
- ``specimens``, ``featurecheck``, ``gallery``: single-specimen crops, the feature-separation measurement and the
  README pictures.
- commands: cmd_render, cmd_synth, cmd_record; benchmark: bench.
"""
