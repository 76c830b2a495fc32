"""The SAIA PCD4.H3 servo positioning module (spec pcd4h3.md): work in progress.

So far the S-Bus host link's framing (:mod:`devsim.devices.pcd4h3.sbus`: serial data mode with
byte stuffing and CRC, Ether-S-Bus frames, the command set of §9.4) and the library's numbers
(:mod:`devsim.devices.pcd4h3.units`: FFP, counts, velocity and acceleration registers) and the
LM628's profile generator per sample (:mod:`devsim.devices.pcd4h3.trajectory`) and its PID
filter with the motor it drives (:mod:`devsim.devices.pcd4h3.pid`), the chip around them with its
commands, status and signals (:mod:`devsim.devices.pcd4h3.lm628`) and its runner on the device
clock that rests when the chip settles (:mod:`devsim.devices.pcd4h3.stepper`), and the library's
register blocks and flag fields (:mod:`devsim.devices.pcd4h3.layout`) with AxInit and AxHndlg over
them (:mod:`devsim.devices.pcd4h3.library`), each tested with the spec's vectors or the loop's
closed form.  The kind (the LM628 controller, the PCD9.H3E1 library, the PLC around it, the
faces) is not built or registered yet.
"""
