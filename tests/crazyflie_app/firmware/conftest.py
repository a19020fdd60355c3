"""What the firmware-emulation tests share: a hover setpoint and the height it holds."""
from crazyflie_app.firmware.commander import modeAbs, modeVelocity

HEIGHT = 1.0
HEIGHT_TOLERANCE = 0.05


def hover(sp, vx=0.0, vy=0.0, z=HEIGHT):
    """Fill ``sp`` with a body-frame velocity hover at height ``z`` (the setpoint an app streams)."""
    sp.mode.x = sp.mode.y = modeVelocity
    sp.mode.z = sp.mode.yaw = modeAbs
    sp.velocity.x, sp.velocity.y, sp.position.z = vx, vy, z
    sp.velocity_body = True
    return sp
