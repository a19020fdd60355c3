"""Where a flight's CPU time goes, by stage of the frame's way (docs/DESIGN.md): render -> module -> wire ->
app -> firmware, and the harness around them. From a profiled flight (flight option ``profile``): the
scheduler's CPU time per task and the camera's own render / module split."""

STAGES = ("render", "module", "wire", "app", "firmware", "harness")
# the emulated Crazyflie's and the harness' tasks, by stage (the camera task also renders and runs the module)
TASK_STAGES = {"STABILIZER": "firmware", "APP": "app", "CAMERA": "app", "UART2_RX": "wire", "HARNESS_CAMERA": "wire",
               "HARNESS_MONITOR": "harness"}


def stage_split(task_cpu_s: dict[str, float], camera_cpu_s: dict[str, float] | None = None) -> dict[str, float]:
    """{stage: CPU seconds}: each task's time to its stage; the camera's render and module time moved out of
    the harness camera task (which calls them) into their own stages."""
    stages = dict.fromkeys(STAGES, 0.0)
    for name, cpu in task_cpu_s.items():
        stages[TASK_STAGES.get(name, "harness")] += cpu
    for stage in ("render", "module"):
        spent = (camera_cpu_s or {}).get(stage, 0.0)
        stages[stage] += spent
        stages["wire"] -= spent
    return {stage: round(max(cpu, 0.0), 3) for stage, cpu in stages.items()}
