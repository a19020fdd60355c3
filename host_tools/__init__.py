"""ForaNav host tools: simulator, harness, replay, training, benchmarks, deploy, plots, telemetry."""
