"""FreeRTOS as the app layer sees it: a 1 ms tick clock and cooperative tasks that sleep with vTaskDelay.

A task is a Python generator; ``yield v_task_delay(ticks)`` suspends it like ``vTaskDelay(M2T(ms))``
(a relative delay: a loop of {work; vTaskDelay(10)} runs every 10 ms because work takes no simulated time).
The scheduler runs the task that wakes earliest; tasks waking on the same tick run in priority order (higher
first, as the preemptive FreeRTOS scheduler would), then in creation order. Each task runs atomically between
two of its own delays, so shared state needs no locks; FreeRTOS time slicing at equal priority is not modelled.
Everything is deterministic: no wall clock, no threads.
"""
import heapq
import time
from collections.abc import Iterator

TICK_RATE_HZ = 1000  # configTICK_RATE_HZ: 1 tick = 1 ms
PORT_MAX_DELAY = 0xFFFFFFFF  # portMAX_DELAY: park the task forever


def m2t(ms: float) -> int:
    """M2T(ms): milliseconds to ticks (identity at 1 kHz)."""
    return int(ms)


def t2m(ticks: float) -> int:
    """T2M(ticks): ticks to milliseconds (identity at 1 kHz)."""
    return int(ticks)


def f2t(hz: float) -> int:
    """F2T(hz): the period of a rate, in ticks."""
    return int(round(TICK_RATE_HZ / hz))


class Delay:
    """What a task yields: sleep this many ticks (vTaskDelay)."""

    __slots__ = ("ticks",)

    def __init__(self, ticks: int):
        if ticks < 0:
            raise ValueError("vTaskDelay: negative delay %r" % ticks)
        self.ticks = int(ticks)


Task = Iterator[Delay]  # a task: a generator that yields v_task_delay(ticks)


def v_task_delay(ticks: int) -> Delay:
    """vTaskDelay(ticks): ``yield v_task_delay(M2T(10))`` inside a task."""
    return Delay(ticks)


class Scheduler:
    """The tick clock and the ready list.

    ``x_task_get_tick_count()`` is the current tick. ``x_task_create(generator, name, priority)`` adds a task
    that starts at the current tick. ``run_until(tick)`` runs every task due before ``tick`` and leaves the
    clock at ``tick``. A task that returns is deleted (an app task that must park should
    ``yield v_task_delay(PORT_MAX_DELAY)``).
    """

    def __init__(self):
        self._now = 0
        self._ready = []  # heap of (wake_tick, -priority, creation_order, name, generator)
        self._created = 0
        self.stopped = False
        self.task_cpu_s = None  # {task name: CPU seconds in its steps}, once profile() is called

    def profile(self) -> None:
        """Count the CPU time each task spends (benchmarks: where a flight's time goes); off by default."""
        self.task_cpu_s = {}

    def x_task_get_tick_count(self) -> int:
        return self._now

    def x_task_create(self, generator: Task, name: str, priority: int) -> None:
        heapq.heappush(self._ready, (self._now, -priority, self._created, name, generator))
        self._created += 1

    def task_names(self) -> list[str]:
        return sorted(entry[3] for entry in self._ready)

    def run_until(self, tick: int) -> bool:
        """Run tasks in wake order up to (excluding) ``tick``; return False if stop() was called."""
        while self._ready and self._ready[0][0] < tick and not self.stopped:
            wake, neg_priority, order, name, task = heapq.heappop(self._ready)
            self._now = wake
            cpu0 = time.process_time() if self.task_cpu_s is not None else None
            try:
                delay = next(task)
            except StopIteration:
                continue
            finally:
                if cpu0 is not None:
                    self.task_cpu_s[name] = self.task_cpu_s.get(name, 0.0) + time.process_time() - cpu0
            if not isinstance(delay, Delay):
                raise TypeError("task %s yielded %r, expected v_task_delay(ticks)" % (name, delay))
            if delay.ticks >= PORT_MAX_DELAY:
                continue  # parked forever: drop it from the ready list
            heapq.heappush(self._ready, (wake + max(delay.ticks, 1), neg_priority, order, name, task))
        if not self.stopped:
            self._now = max(self._now, tick)
        return not self.stopped

    def stop(self) -> None:
        self.stopped = True
