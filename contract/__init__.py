"""The facts two parts of gliderplan share, each defined once.

The checker, the code generator, the planner, the plan file, the simulator, the
serial protocol and the C runtime all rest on the numbers below. Python imports them
from here; the C runtime includes `runtime/include/gp_contract.h`, which is generated
from this module (`python -m gliderplan.contract`) and compared with it by the tests.
Change a fact here, regenerate the header, and every part follows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

# ---- limits of the runtime's tables and of the plan file ----------------------------
# The C runtime holds a mission in static tables with uint8_t counts, and the plan file
# and its reader have fixed sizes. `gliderplan check` refuses a mission past any of
# them, so that nothing it accepts is refused later for its size.

MAX_STATES = 64  # states of a mission (the plan file's `states` line: 1..64)
MAX_VARIABLES = 64  # variables of a mission
MAX_STACK_DEPTH = 32  # the state stack: the largest `stack N` (or --max-stack)
DEFAULT_STACK_DEPTH = 8  # the state stack of a mission without `stack N`
MAX_EVENTS_PER_STATE = 255  # events of one state (a uint8_t count)
MAX_PROFILE_ALTERNATIVES = 8  # `flightprofile a | b | ...` alternatives of one state
MAX_PROFILE_ARGS = 7  # arguments of one flight profile
MAX_ROUTE_POINTS = 64  # (lat, lon) points of one state's route
MAX_SWEEP_WAYPOINTS = 256  # waypoints a `sweep` route expands to
# Operators and calls nested in one expression (a sum of n terms is n - 1 deep). Every
# stage that reads a mission walks its expressions (the mission's hash, the C code, the
# simulator's compiled conditions): a bound keeps them all within Python's stack.
MAX_EXPRESSION_DEPTH = 100
# Entries the parser's stack may hold: brackets and operators open at once (an expression
# MAX_EXPRESSION_DEPTH deep, bracketed at every level, needs fewer). Parsing stays linear
# in the text and a 16 MiB file of brackets is refused at its first token past it.
MAX_PARSE_DEPTH = 1000
# Scenarios one Monte Carlo run or confidence plan may fly: a million month-long flights
# is days of work on a workstation, and more than any stated confidence needs in practice
MAX_SCENARIOS = 1_000_000
# Years a simulated run may start in (inclusive): its dates, and a horizon on, are written
# by every output (NetCDF's seconds since 1970, ISO 8601 text, OG1.0's YYYYmmddTHHMMss)
START_YEARS = (1970, 2100)
MAX_NAME_LENGTH = 32  # characters of a mission, state or computer name in a plan file
MAX_PLAN_SENSORS = 16  # `sensor` lines of one state block of a plan file
MAX_PLAN_BYTES = 65536  # size of a plan file [bytes]
MAX_PLAN_LINE_BYTES = 255  # length of a plan-file line, its LF included [bytes]
MAX_PLAN_COMPONENTS = 16  # energy components a plan predicts (its `components` line)
MAX_PLAN_ASSUMPTIONS = 255  # `assume` lines of a plan file (a uint8_t count)
PLAN_FORMAT_VERSION = 3  # the plan file's `GPPLAN` line (docs/plan-format.md)

# ---- what a plan may ask for ---------------------------------------------------------
# A plan's numbers are bounded so that no finite but absurd value (a ballast of 1e300 cc,
# a clock the board does not have) reaches the vehicle. The vehicle's pump and the
# board's clocks come from its power-model files through the compiled mission; the
# bounds below hold for every vehicle. The runtime's reader, `compile --plan` and `sim`
# refuse a plan past any of them.
MAX_PLAN_TIME_S = 315_360_000.0  # [s] a cycle, a sensor period, a state's predicted time (10 y)
MAX_PLAN_SPEED_MPS = 2.0  # [m/s] a planned horizontal speed (a glider makes 0.2-0.5)
# [W] a yo's thruster's commanded power (the Slocum G3 hybrid's commands 1-9 W)
MAX_PLAN_THRUST_W = 100.0
MAX_PLAN_ENERGY_J = 1e10  # [J] a budget or prediction (the largest Slocum pack is 12 MJ)
MAX_PLAN_INFLECTIONS = 1e9  # a state's predicted inflections (as many as its visits may be)
MAX_BOARD_CLOCKS = 8  # clocks of one board the compiled mission lists
# A sensor's weight in the quality objective is relative to the others': a ratio past this
# is beyond what the solver resolves (its tolerance is ~1e-8), and 1e308 overflowed it.
MAX_SENSOR_WEIGHT = 1e6
CLOCK_TOLERANCE_MHZ = 1e-6  # [MHz] a plan's clock is the board's within this
NO_BOARD = "none"  # `computer none`: no board to set; its plans' clocks are all 0


def same_clock(clock_mhz: float, board_clock_mhz: float) -> bool:
    """Whether a clock [MHz] is the board's clock `board_clock_mhz`: the one test `check`,
    the planner, the simulator and both plan readers apply (the C reader with
    GP_CLOCK_TOLERANCE_MHZ)."""
    return abs(clock_mhz - board_clock_mhz) <= CLOCK_TOLERANCE_MHZ


# A plan's figures are written with 9 significant digits: two that should agree (a duty and
# its bound, the prediction and its states' sum) agree within this relative tolerance.
PLAN_ROUNDING = 1e-6


class EnvelopeAction(IntEnum):
    """What the runtime does with a command outside the vehicle's envelope.

    The vehicle file's `[envelope] action` chooses; every held command is logged."""

    FAULT = 0  # release control to the glider's own layered control, as a mission fault
    SURFACE = 1  # the mission's abort: it ends there, the glider surfaces and holds
    CLAMP = 2  # hold the command at the envelope's edge, fly on (a band or rate: as SURFACE)


class EnvelopeLimit(IntEnum):
    """Which limit of the envelope a command broke (the event log's `envelope` record)."""

    NONE = 0
    DEPTH = 1  # a depth target, or a yo's end, outside 0..max_depth
    PITCH = 2  # |pitch| above max_pitch
    BALLAST = 3  # |pumped volume| above the pump's max_ballast
    BAND = 4  # a yo band thinner than min_yo_band: it would turn all the time
    INFLECTION = 5  # a yo turned again sooner than its pump can move a full stroke
    SPEED = 6  # a propelled speed outside the propulsion's range (0: the motor off)
    THRUST = 7  # a thruster's commanded power outside its range (0: off)
    PUMP_ENERGY = 8  # the pump's energy over the last hour above its rated mean power


@dataclass(frozen=True)
class PumpEnergy:
    """The buoyancy pump's energy per volume moved at a depth z [m]: out (buoyancy up,
    against sea pressure) (out + out_per_m z) per cc, in max(0, in + in_per_m z) per cc
    [J cc-1, J cc-1 m-1] (`power_models.vehicle.Vehicle.pump_energy_j`)."""

    out_j_per_cc: float = 0.0
    out_j_per_cc_m: float = 0.0
    in_j_per_cc: float = 0.0
    in_j_per_cc_m: float = 0.0


@dataclass(frozen=True)
class Envelope:
    """The vehicle's rating that the runtime holds every command to, every tick, whatever
    the events computed (docs/pilot.md, The envelope). From the vehicle file's
    `[envelope]` table and its propulsion and pump figures
    (`power_models.vehicle_figures.derive_envelope`), compiled into the mission
    (`gp_mission.envelope`)."""

    max_depth_m: float  # [m] deepest depth target or yo end
    max_pitch_rad: float  # [rad] largest |pitch| commanded
    min_yo_band_m: float  # [m] thinnest yo band (max - min depth)
    min_inflection_s: float  # [s] shortest time between two turns of a yo
    action: EnvelopeAction
    # [m/s] a propelled speed is 0 (the motor off) or within these: its propulsion's range
    # (0, 0: no propulsion)
    speed_range_mps: tuple[float, float] = (0.0, 0.0)
    # [W] a thruster's commanded power is 0 (off) or within these (0, 0: no thruster)
    thrust_range_w: tuple[float, float] = (0.0, 0.0)
    # [rad/s] the fastest the vehicle turns: every heading command turns no faster (inf: any)
    max_turn_rate_rad_s: float = math.inf
    # [W] the pump's mean power over an hour (its energy per hour / 3600 s; inf: no limit)
    max_pump_power_w: float = math.inf
    pump: PumpEnergy = PumpEnergy()

    def __post_init__(self) -> None:
        ranges = (self.speed_range_mps, self.thrust_range_w)
        if not (self.max_depth_m > 0 and 0 < self.max_pitch_rad < 1.5707963267948966
                and 0 <= self.min_yo_band_m < self.max_depth_m and self.min_inflection_s >= 0
                and all(0 <= low <= high < math.inf for low, high in ranges)
                and self.max_turn_rate_rad_s > 0 and self.max_pump_power_w > 0
                and all(math.isfinite(f) for f in vars(self.pump).values())):
            raise ValueError(f"not an envelope: {self}")


@dataclass(frozen=True)
class FlightLimits:
    """The figures of one mission, vehicle and board that bound a plan: the code generator
    writes them into the compiled mission (`gp_mission`: `max_ballast_cc`, `clocks_mhz`,
    `bounds`), `contract.plan_check.plan_problem` holds a plan to them in Python and
    `gp_plan_check` in C (`planner.limits.flight_limits` loads them). The fields after
    `clocks_mhz` default to no bound beyond the contract's (a mission table made by hand),
    but for `envelope`."""

    default_ballast_cc: float  # [cc] flown where no plan sets one
    max_ballast_cc: float  # [cc] the pump's volume either side of neutral
    clocks_mhz: tuple[float, ...]  # [MHz] the board's clocks, slowest first
    board: str | None = None  # the board's name a plan names (or NO_BOARD); None: any
    max_budget_j: float = MAX_PLAN_ENERGY_J  # [J] the battery less its reserve
    pitch_range_rad: tuple[float, float] = (0.0, math.pi / 2)  # [rad] commanded, open
    max_speed_mps: float = MAX_PLAN_SPEED_MPS  # [m/s] the vehicle's fastest glide
    # [1] per state, per sensor it logs with a device and a duty (`auto` or fixed), in its
    # order: (name, least, most duty the mission allows); (): no bounds
    duty_bounds: tuple[tuple[tuple[str, float, float], ...], ...] = ()
    # [cc] per state, per profile alternative: the volume a plan's ballast must exceed for
    # the glider to leave its turning depth (its trim over the band); () : 0
    min_ballast_cc: tuple[tuple[float, ...], ...] = ()
    # [m/s] a propelled profile's `auto` speed where no plan sets one (0: no propulsion)
    unplanned_speed_mps: float = field(default=0.0, kw_only=True)
    # per state, the alternative flown where no plan sets one: the first the vehicle can
    # fly (a propeller AUV skips a yo); empty: the first of each state
    unplanned_profiles: tuple[int, ...] = field(default=(), kw_only=True)
    # [m/s] the speeds a level (propelled) profile may fly: its propulsion's range
    propelled_speed_mps: tuple[float, float] = field(default=(0.0, MAX_PLAN_SPEED_MPS),
                                                     kw_only=True)
    # [W] a yo's thruster command, where one is on: its power-command range
    thrust_range_w: tuple[float, float] = field(default=(0.0, MAX_PLAN_THRUST_W), kw_only=True)
    # the vehicle's rating every command is held to in flight (`gp_mission.envelope`):
    # always given, by name
    envelope: Envelope = field(kw_only=True)

    def __post_init__(self) -> None:
        if not 1 <= len(self.clocks_mhz) <= MAX_BOARD_CLOCKS:
            raise ValueError(f"a board has 1..{MAX_BOARD_CLOCKS} clocks, not "
                             f"{len(self.clocks_mhz)}")

    def unplanned_profile(self, state: int) -> int:
        """The alternative state `state` (its index) flies without a plan."""
        return self.unplanned_profiles[state] if self.unplanned_profiles else 0

    def has_clock(self, clock_mhz: float) -> bool:
        """Whether the board has the clock `clock_mhz` [MHz] (`same_clock`)."""
        return any(same_clock(clock_mhz, c) for c in self.clocks_mhz)


# ---- signed plans (docs/plan-format.md) ---------------------------------------------
PLAN_KEY_BYTES = 32  # [bytes] of the HMAC-SHA256 key provisioned on the vehicle
MAX_PLAN_SEQUENCE = 4_294_967_295  # a signed plan's `seq` (a u32); 1 is the first

# ---- files gliderplan reads ----------------------------------------------------------
# Every file a user names (missions, plans, board, battery, vehicle, sensor, scenario and
# ocean files, run results) is read through `contract.files.read_input`, which refuses a
# larger file and anything but a regular file (a device such as /dev/zero, a named pipe)
# before reading a byte of it.
MAX_INPUT_BYTES = 16 * 1024 * 1024  # [bytes] far beyond any real input; guards the readers
# Data files (TOML model and scenario files, JSON reports and summaries) are parsed by
# `contract.files.parse_data`: tables and arrays nested deeper than this, or a number that
# is not finite (TOML and Python's JSON read `nan` and `inf`), are refused with the key.
MAX_DATA_DEPTH = 32  # the shipped files nest 3 deep, the JSON reports 6

# ---- the sensor array ----------------------------------------------------------------


@dataclass(frozen=True)
class SensorInfo:
    """A value readable in conditions and loggable in `sensors`: one the glider measures,
    or (source "runtime") one the runtime's own routines know, which it writes into its
    sensor array before each tick's events and the science computer never sends."""

    name: str
    index: int  # position in the sensor array (protocol and runtime)
    unit: str  # SI unit of the value
    device: str | None  # power-model device that produces it; None: flight sensor, in hotel load
    description: str
    source: str = "glider"  # "glider": sent by the science computer; "runtime": see above


# The science computer's sensor array: SENSORS bit i of the link and the runtime's
# sensors[i] are the sensor of index i. Order is the layout; append only, never reorder
# (it is a wire format). A new sensor is one entry here (and, if it draws power of its
# own, a device file in power_models/data).
SENSORS: tuple[SensorInfo, ...] = (
    SensorInfo("missiontime", 0, "s", None, "time since the mission started"),
    SensorInfo("depth", 1, "m", None, "depth below the surface, positive down"),
    SensorInfo("pitch", 2, "rad", None, "vehicle pitch, positive nose up"),
    SensorInfo("roll", 3, "rad", None, "vehicle roll"),
    SensorInfo("heading", 4, "rad", None, "magnetic heading"),
    SensorInfo("altitude", 5, "m", None, "height above the sea floor"),
    SensorInfo("lat", 6, "DDMM.MMMM", None, "latitude, Slocum degrees and minutes"),
    SensorInfo("lon", 7, "DDMM.MMMM", None, "longitude, Slocum degrees and minutes"),
    SensorInfo("battery", 8, "V", None, "battery voltage"),
    SensorInfo("temp", 9, "degC", "ctd", "water temperature (CTD)"),
    SensorInfo("conductivity", 10, "S/m", "ctd", "water conductivity (CTD)"),
    SensorInfo("salinity", 11, "PSU", "ctd", "practical salinity (CTD)"),
    SensorInfo("oxygen", 12, "umol/kg", "optode", "dissolved oxygen (optode)"),
    SensorInfo("chlorophyll", 13, "ug/l", "optics", "chlorophyll fluorescence (optics)"),
    SensorInfo("backscatter", 14, "1/m", "optics", "optical backscatter (optics)"),
    SensorInfo("current", 15, "m/s", "adcp", "water current speed (ADCP)"),
    SensorInfo("modem", 16, "B", "modem", "bytes received by the acoustic modem"),
    SensorInfo("halfcycle", 17, "1", None, "the yo's leg flown since the profile was entered "
               "(1: the first dive or climb); 0 outside a yo", "runtime"),
    SensorInfo("wptdist", 18, "m", None, "distance to the waypoint the route flies to; NaN "
               "without one or without a position", "runtime"),
    SensorInfo("timeofday", 19, "s", None, "UTC time of day of the glider's clock, 0 at "
               "midnight"),
    SensorInfo("energy_left", 20, "J", None,
               "energy left in the battery: its capacity less what the coulomb counter "
               "counted (the energy guard reads it)"),
    SensorInfo("wptreached", 21, "1", None, "waypoints the route has reached since the state "
               "was entered (a goto list counts on, lap after lap); 0 for nav and noheading",
               "runtime"),
    SensorInfo("groundspeed", 22, "m/s", "dvl", "speed over the sea floor (DVL bottom track)"),
    SensorInfo("shear", 23, "1/s", "logger",
               "microstructure velocity shear (microstructure logger)"),
)
N_SENSORS = len(SENSORS)  # the array's length (HELLO's `n_sensors`); at most 32 (u32 masks)
# The sensor devices, each once, in the array's order: what a surfacing report counts the
# on-time of, by its place here (docs/plan-update.md), and what the simulator bills.
SENSOR_DEVICES: tuple[str, ...] = tuple(dict.fromkeys(s.device for s in SENSORS if s.device))
# Sensors without a device of their own: always powered while logged, in the hotel load.
FLIGHT_SENSORS_MASK = sum(1 << s.index for s in SENSORS if s.device is None)
# The runtime's own readings (never on the link).
RUNTIME_READINGS_MASK = sum(1 << s.index for s in SENSORS if s.source == "runtime")


# ---- the library routines (docs/pilot.md) -------------------------------------------
# The C runtime and the Python reference executor fly alike, bit for bit.

SURFACE_PITCH_RAD = 0.454  # [rad] pitch of the climb to the surface
TRACK_WINDOW = 64  # (depth, temp) readings the thermocline tracker keeps per leg
# where yo and thermotrackyo take their altimeter stop [m] (the registry's `altitude`)
YO_ALTITUDE_ARG = 4  # yo's argument: a dive turns at this height above the sea floor
THERMOTRACKYO_ALTITUDE_ARG = 6  # thermotrackyo's argument, as yo's
WAYPOINT_RADIUS_M = 50.0  # [m] a waypoint closer than this is reached
EARTH_RADIUS_M = 6371000.0  # [m] of the sphere positions and headings are computed on


# ---- time and workload --------------------------------------------------------------

# The science computer writes the sensor array every 2-4 s: one SENSORS frame, one
# COMMAND and one step of the mission per tick. The planner's occupancy and the
# simulator's clock both run on it.
TICK_S = 4.0  # [s]
# The runtime's whole tick on a board: decode a frame, check events, run the library
# routine, encode the COMMAND, journal the tick, and the kernel's work for all of it. An
# assumption, kept because no board's whole tick is measured: the runtime's own code is
# (a board file's `runtime_instructions`, a small part of this), the system calls, the
# serial line's interrupts and the journal's fdatasync to flash are not. Under 0.1 %
# busy at 133 MHz and a 4 s tick. The planner prices the computer with it, the
# simulator bills it, compare-sbc sets it beside each board's measured code.
RUNTIME_CYCLES_PER_TICK = 200_000.0  # [cycles]
# A mission without `horizon` is planned over this time, and a run of it (sim, montecarlo)
# ends here if it has not exited: the plan's budget and the flight cover the same time.
DEFAULT_HORIZON_S = 30 * 86400.0  # [s] 30 days
# A simulated run keeps one row per tick in memory (about 400 bytes of columns, then the
# tables written from them): a run of more ticks is refused before it starts, saying how
# long it would be (`sim --tick 0.1` of a 30-day mission is 26 million ticks, ~10 GB).
MAX_SIMULATED_TICKS = 3_000_000  # 139 days at the 4 s tick; ~1.3 GB
# Worker processes of one Monte Carlo run or confidence plan on this machine: a local pool
# starts them all at once (`--workers 100000` forked until the machine had no more).
MAX_WORKERS = 256


# ---- energy components --------------------------------------------------------------


class Component:
    """Names of the energy components, as the plan predicts them and the simulator bills
    them; the sensor devices (`SensorInfo.device`) are components under their own names."""

    HOTEL = "hotel"  # the vehicle's base load while gliding
    PUMP = "pump"  # buoyancy pump runs
    PITCH = "pitch"  # battery shifts at inflections
    SURFACE = "surface"  # the base load at the surface
    IRIDIUM = "iridium"  # satellite calls at the surface
    PROPULSION = "propulsion"  # a propeller's or a glider's thruster's motor
    COMPUTER = "computer"  # the single-board computer running the mission
    SENSORS = "sensors"  # the sensor devices together, where they are not billed one by one


VEHICLE_COMPONENTS: tuple[str, ...] = (Component.HOTEL, Component.PUMP, Component.PITCH,
                                       Component.SURFACE, Component.IRIDIUM,
                                       Component.PROPULSION)


# ---- the serial link (docs/protocol.md) ---------------------------------------------

PROTOCOL_VERSION = 3  # 2: COMMANDs as changes against a base, SENSORS without a mask;
# 3: COMMAND's speed and thrust (propelled flight)
MAX_PAYLOAD = 240  # [bytes] of one frame's payload
MAX_WIRE = 250  # [bytes] of COBS before the delimiter that a receiver accepts
PLAN_PIECE = 200  # [bytes] of plan file per PLAN frame
MAX_LINK_PLAN = 65535  # [bytes] of a plan sent over the link (PLAN's `total` is a u16)
# [bytes] of one Iridium SBD mobile-terminated message, the way a plan reaches a glider at
# the surface (Iridium Short Burst Data Service Developers Guide: MT payload <= 1890 bytes)
SBD_MT_MESSAGE_BYTES = 1890
# The short Iridium SBD messages fleets use at each surfacing (Iridium SBD service: 340
# bytes mobile-originated, 270 mobile-terminated): a surfacing report goes up in one, a
# plan update comes down in one.
SBD_MO_SHORT_BYTES = 340  # [bytes] of one short message up, glider to shore
SBD_MT_SHORT_BYTES = 270  # [bytes] of one short message down, shore to glider
COMMAND_MAX_SIZE = 46  # [bytes] of a COMMAND payload that carries every field
MISSION_HASH_BYTES = 32  # [bytes] of HELLO's mission hash (raw SHA-256 of the mission)
# [bytes] of HELLO before the mission's name: protocol, n_sensors, read_mask, hash, name_len
HELLO_FIXED_BYTES = 1 + 1 + 4 + MISSION_HASH_BYTES + 1
BAUD = 115200  # 8N1: 10 bits per byte on the line
# [ms] a frame unanswered this long is sent again (science computer's frames, runtime's HELLO)
RETRANSMIT_MS = 200
# [s] the watchdog: the runtime releases the glider after this long without a valid frame
LINK_TIMEOUT_S = 10.0


class MessageType(IntEnum):
    """The type byte of a frame's header."""

    HELLO = 0x01
    SENSORS = 0x02
    COMMAND = 0x03
    RELEASE = 0x04
    PLAN = 0x05
    PLAN_STATUS = 0x06
    PLAN_UPDATE = 0x07  # pieces of a plan update (docs/plan-update.md), as PLAN carries plans
    UPDATE_STATUS = 0x08  # what became of the update: applied, or why not
    NAK = 0x7F


class TransitionKind(IntEnum):
    """COMMAND's `transition` field, the event log's `kind` and an event's action."""

    NONE = 0
    START = 1
    GOTO = 2
    CALL = 3
    RETURN = 4
    EXIT = 5
    RESERVE = 6  # the energy guard ended the mission: the battery reached its reserve
    ENVELOPE = 7  # the envelope guard ended the mission: a command outside the vehicle's rating


# The language's action words and the kinds they make.
TRANSITION_BY_ACTION: dict[str, TransitionKind] = {
    "goto": TransitionKind.GOTO, "call": TransitionKind.CALL,
    "return": TransitionKind.RETURN, "exit": TransitionKind.EXIT}
# Every kind's name in a trace and in the runtime's event log.
TRANSITION_NAMES: dict[TransitionKind, str] = {
    TransitionKind.START: "start", **{k: a for a, k in TRANSITION_BY_ACTION.items()},
    TransitionKind.RESERVE: "reserve", TransitionKind.ENVELOPE: "envelope"}

NO_STATE = 0xFF  # COMMAND's `state` once exited; `from`/`to` of no state

# COMMAND's `flags` (plain ints: the simulator builds a COMMAND every tick).
FLAG_SURFACE = 1 << 0  # go to (or stay at) the surface
FLAG_DONE = 1 << 1  # the mission exited
FLAG_CLIMBING = 1 << 2  # else diving
FLAG_HEADING = 1 << 3  # `heading_rad` is valid
FLAG_ENVELOPE = 1 << 4  # the envelope guard held this command at the vehicle's rating
FLAG_HEADING_HOLD = 1 << 5  # `heading_rad` is held as it is, uncorrected for the current

# SENSORS's `flags`; the other bits are reserved (0), and a SENSORS with one set is dropped.
SENSORS_MASK = 1 << 0  # a u32 mask follows; else the values are those of HELLO's read_mask
SENSORS_RESYNC = 1 << 1  # answer with a whole COMMAND: the last one could not be applied


class CommandField(IntEnum):
    """A COMMAND's fields in wire order: bit i of its `fields` says that field i follows.
    The names are those of `protocol.Command`; append only (it is a wire format)."""

    STATE = 0  # u8 state index after the tick, NO_STATE once exited
    STACK_DEPTH = 1  # u8 stack depth after the tick
    TRANSITION = 2  # u8 TransitionKind of the tick (NONE on most)
    FROM_STATE = 3  # u8 state the transition left, NO_STATE: none
    TO_STATE = 4  # u8 state the transition entered, NO_STATE: none
    PROFILE = 5  # u8 index of the flight-profile alternative flown
    FLAGS = 6  # u8 FLAG_* bits
    DEPTH_TARGET_M = 7  # f32 [m]
    PITCH_RAD = 8  # f32 [rad], positive nose up
    BALLAST_CC = 9  # f32 [cc] pumped from neutral, positive buoyant
    HEADING_RAD = 10  # f32 [rad] true, clockwise from north (valid with FLAG_HEADING)
    SENSOR_POWER = 11  # u32 bit i: power sensor i's device
    EVENT_COUNT = 12  # u32 events fired so far
    SPEED_MPS = 13  # f32 [m/s] through the water on the propeller; 0: none (a glide)
    THRUST_W = 14  # f32 [W] a glider's thruster's commanded power assisting a yo; 0: off


# struct format of each COMMAND field, in CommandField order
COMMAND_FIELD_FORMATS = "BBBBBBBffffIIff"


class ReleaseReason(IntEnum):
    """RELEASE's `reason`: why the runtime gave control back to the glider."""

    LINK_SILENT = 1  # no valid frame for the link timeout (the watchdog)
    INTERNAL_ERROR = 2  # a mission fault, I/O that failed, a crash or a stop signal
    MISSION_EXITED = 3
    ENERGY_RESERVE = 4  # the energy guard ended the mission: surface and hold
    ENVELOPE = 5  # a command outside the vehicle's rating: the envelope guard acted


class RuntimeExit(IntEnum):
    """Exit status of a mission binary (runtime/README.md)."""

    DONE = 0  # the mission exited
    BAD_INPUT = 1  # bad arguments, plan or checkpoint
    LINK_LOST = 3  # the watchdog: the link went silent
    INTERNAL = 4  # a mission fault, I/O that failed, a crash or a stop signal
    RESERVE = 5  # the energy guard ended the mission: the battery reached its reserve
    ENVELOPE = 6  # a command outside the vehicle's rating: the envelope guard ended it


# ---- plan updates (docs/plan-update.md) ----------------------------------------------
# A plan update is a signed binary delta against the plan the glider holds: it changes
# what the glider flies (the fields of UpdateField) and fits one short Iridium message.
UPDATE_FORMAT_VERSION = 1  # the update's version byte; a reader rejects any other
MAX_UPDATE_BYTES = SBD_MT_SHORT_BYTES  # [bytes] of one update, its tag included
UPDATE_HASH_BYTES = 8  # [bytes] of SHA-256 that name the plan an update is for, and its result
UPDATE_HEADER_BYTES = 28  # [bytes] magic, version, seqs, hashes, the count of changes
UPDATE_MAX_DIGITS = 15  # decimal digits of a value's mantissa: exact in a double
UPDATE_MAX_EXPONENT = 20  # a value is mantissa x 10^exponent, |exponent| at most this


class UpdateField(IntEnum):
    """What a change of a plan update sets (a field of one plan-file line).

    Each names the line's keyword and the field's place after it (docs/plan-format.md);
    append only: it is a wire format."""

    STATE_CLOCK = 1  # `state NAME CLOCK_MHZ ...`: field 2
    STATE_CYCLE = 2  # `state ... CYCLE_S ...`: field 3
    POWER_SLEEP = 3  # `power SLEEP CYCLES_PER_TICK`: field 1
    POWER_CYCLES = 4  # field 2
    SENSOR_PERIOD = 5  # `sensor NAME PERIOD_S ON_S`: field 2
    SENSOR_ON = 6  # field 3
    PROFILE_SHARE = 7  # `profile INDEX SHARE PITCH_RAD BALLAST_CC SPEED_MPS`: field 2
    PROFILE_PITCH = 8  # field 3
    PROFILE_BALLAST = 9  # field 4
    PROFILE_SPEED = 10  # field 5
    PROFILE_THRUST = 11  # `profile ... THRUST_W`: field 6, appended where the line has none


# Each UpdateField that a line may leave out (0 by the format): a change to it on a line
# without it appends it after the line's last field.
UPDATE_OPTIONAL_FIELDS = frozenset({UpdateField.PROFILE_THRUST})


# Each UpdateField's line keyword and the 1-based place of the field after it.
UPDATE_FIELD_LINES: dict[UpdateField, tuple[str, int]] = {
    UpdateField.STATE_CLOCK: ("state", 2), UpdateField.STATE_CYCLE: ("state", 3),
    UpdateField.POWER_SLEEP: ("power", 1), UpdateField.POWER_CYCLES: ("power", 2),
    UpdateField.SENSOR_PERIOD: ("sensor", 2), UpdateField.SENSOR_ON: ("sensor", 3),
    UpdateField.PROFILE_SHARE: ("profile", 2), UpdateField.PROFILE_PITCH: ("profile", 3),
    UpdateField.PROFILE_BALLAST: ("profile", 4), UpdateField.PROFILE_SPEED: ("profile", 5),
    UpdateField.PROFILE_THRUST: ("profile", 6)}


class UpdateStatus(IntEnum):
    """UPDATE_STATUS's `status`: what became of a plan update (docs/plan-update.md)."""

    APPLIED = 0  # the new plan is in force from the next tick
    DUPLICATE = 1  # the update that made the plan in force, sent again: nothing to do
    NO_KEY = 2  # no key is provisioned on the vehicle: no update is trusted
    MALFORMED = 3  # not an update, another version, or a change that cannot be made
    FORGED = 4  # the tag does not match: changed after signing, or another key
    STALE = 5  # not newer than the plan in force: replayed or stale
    NOT_HELD = 6  # made against a plan the vehicle does not hold
    OUT_OF_ORDER = 7  # made against a plan newer than the one in force: one is missing
    BAD_PLAN = 8  # the plan it makes breaks the format or the vehicle's limits
    NOT_STORED = 9  # the new plan could not be stored: the plan in force stays



# ---- the command line ---------------------------------------------------------------


class ExitCode(IntEnum):
    """Exit status of every `gliderplan` command (README.md)."""

    OK = 0
    BAD_INPUT = 1  # a bad mission, an infeasible budget, a failed validation
    USAGE = 2  # bad command-line usage: a missing file, a malformed option
    OVER_BUDGET = 3  # a simulated run broke its plan's energy budget
    OVER_PREDICTION = 4  # with --strict-prediction: a run spent more than its plan predicted
    ENVELOPE = 5  # a simulated run commanded the vehicle outside its rating (the envelope guard)
    LINK_FAILED = 6  # a simulated run ended on a link failure (all it flew is written)
    INTERNAL = 70  # a bug in gliderplan (EX_SOFTWARE of sysexits.h)
    INTERRUPTED = 130  # stopped by Ctrl-C (128 + SIGINT)
    TERMINATED = 143  # stopped by SIGTERM, as by Ctrl-C: outputs written, children stopped
    BROKEN_PIPE = 141  # the reader of stdout went away (`| head`): stopped quietly (128 + SIGPIPE)
