"""The Slocum science bay's instruments, once: the `sample` behaviour's `sensor_type`
number, the instrument's name, the flight computer's switch for it (`c_<name>_on`, its
sampling interval: < 0 off, 0 as fast as possible, > 0 seconds between samples) and the
power-model device it is (a sensor preset in `data/`), or None for an instrument
gliderplan has no power model of.

The calibration reads each device's on/off state from these switches in the logs; the
Slocum importer turns a `sample` behaviour into the devices it powers.
Source: the `sample` behaviour's enum as SWFSC standard-glider-files `sample_generic.ma`
lists it (Slocum firmware 8.x); `sensor_type` 1 (PROFILE) is the CTD, switched by
`c_profile_on`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ALL_SCIENCE = 0  # sensor_type 0: C_SCIENCE_ALL_ON, every instrument at once


@dataclass(frozen=True)
class Instrument:
    """One instrument of the science bay."""

    sensor_type: int  # the `sample` behaviour's number
    name: str  # Slocum's name, e.g. "FLNTU"
    device: str | None  # power-model device (a sensor preset), None: no model

    @property
    def switch(self) -> str:
        """The flight computer's sampling-interval variable, e.g. `c_flntu_on`, in lower
        case (the firmware writes some with capitals: `c_bb3sloV2_on`, `c_FIRe_on`)."""
        return f"c_{self.name.lower()}_on"


def _instruments(device: str | None, *pairs: tuple[int, str]) -> list[Instrument]:
    return [Instrument(number, name, device) for number, name in pairs]


_TABLE = (
    [Instrument(1, "PROFILE", "ctd")]
    + _instruments("ctd", (14, "WHFCTD"), (59, "CTD41CP2"), (75, "SBE41N_PH"))
    + _instruments("optics", (3, "BB2F"), (4, "BB2C"), (5, "BB2LSS"), (10, "BBFL2S"),
                   (11, "FL3SLO"), (12, "BB3SLO"), (19, "FLNTU"), (20, "FL3SLOV2"),
                   (21, "BB3SLOV2"), (24, "BB3SLOV3"), (25, "BB2FLS"), (26, "BB2FLSV2"),
                   (29, "BB2FV2"), (31, "BBFL2SV2"), (34, "BB2FLSV3"), (37, "BB2FLSV4"),
                   (38, "BB2FLSV5"), (44, "BB2FLSV6"), (45, "FLBBRH"), (46, "FLUR"),
                   (47, "BB2FLSV7"), (48, "FLBBCD"), (50, "C3SFL"), (57, "FLBB"),
                   (61, "FLRH"), (62, "BB2FLSV8"), (67, "SEAOWL"), (74, "BB2FLSV9"),
                   (76, "FL2URRH"), (77, "FLBBBBV1"), (78, "FLBBBBV2"), (80, "FL2PECDOM"),
                   (81, "WETLABSA"), (82, "WETLABSB"), (83, "WETLABSC"))
    + _instruments("optode", (13, "OXY3835"), (27, "OXY3835_WPHASE"), (42, "RINKOII"),
                   (54, "OXY4"), (86, "RBRODO"))
    + _instruments("logger", (39, "LOGGER"), (73, "MICRORIDER"))
    + _instruments("dvl", (43, "DVL"))
    + _instruments("adcp", (64, "AD2CP"))
    + _instruments("modem", (41, "UMODEM"))
    + _instruments(None, (6, "SAM"), (9, "MOTEOPD"), (15, "BAM"), (16, "OCR504R"),
                   (17, "OCR504I"), (18, "BADD"), (22, "OCR507R"), (23, "OCR507I"),
                   (28, "AUVB"), (30, "TARR"), (32, "GLBPS"), (33, "SSCSD"), (35, "FIRE"),
                   (40, "BBAM"), (49, "DMON"), (51, "SUNA"), (52, "SATPAR"), (53, "VSF"),
                   (56, "BSIPAR"), (58, "VR2C"), (60, "ECHOSNDR853"), (63, "UVILUXPAH"),
                   (65, "MINIPROCO2"), (66, "PCO2"), (68, "AZFP"), (69, "UBAT"),
                   (70, "LISST"), (71, "LMS"), (72, "SVS603"), (79, "OBSVR"),
                   (84, "ECHODROID"), (85, "TAU"), (87, "SOLOCAM"), (88, "AMAR"),
                   (89, "VRO"))
)
INSTRUMENTS: dict[int, Instrument] = {i.sensor_type: i for i in _TABLE}
# sensor_type numbers the firmware has deleted (a mission naming one is refused by it)
DELETED = {2: "HS2", 7: "WHPAR", 8: "WHGPBM", 36: "OHF", 55: "GAMMA_RAD5"}


def sampling_duty(interval_s: np.ndarray | float, warmup_s: float, sample_hz: float
                  ) -> np.ndarray:
    """Share of the time [1] an instrument is powered when sampled every `interval_s` [s]
    (a `c_<name>_on` value or a `sample` behaviour's `intersample_time`): 0 when < 0 (off)
    or unknown (NaN), 1 when 0 (as fast as possible); else its warm-up [s] and one sample
    period (1 / `sample_hz` [Hz]) each interval, at most 1."""
    interval = np.asarray(interval_s, float)
    awake = warmup_s + 1.0 / sample_hz
    with np.errstate(divide="ignore", invalid="ignore"):
        duty = np.where(interval > 0.0, np.minimum(awake / interval, 1.0), 1.0)
    return np.where(np.isfinite(interval) & (interval >= 0.0), duty, 0.0)


def devices() -> tuple[str, ...]:
    """Every power-model device an instrument of the table is, in the table's order."""
    return tuple(dict.fromkeys(i.device for i in _TABLE if i.device is not None))


def instruments_of(device: str) -> tuple[Instrument, ...]:
    """The instruments that are `device`."""
    return tuple(i for i in _TABLE if i.device == device)
