/**
 * @file gp_contract.h
 * @brief The facts the runtime shares with the rest of gliderplan, generated
 *        from gliderplan.contract: do not edit; run
 *        `python -m gliderplan.contract > runtime/include/gp_contract.h`.
 */
#ifndef GP_CONTRACT_H
#define GP_CONTRACT_H

/* ---- limits of the mission tables and the plan file */

#define GP_MAX_STATES 64  /**< states of a mission (the plan file's `states` line: 1..64) */
#define GP_MAX_VARIABLES 64  /**< variables of a mission */
#define GP_MAX_STACK_DEPTH 32  /**< the state stack: the largest `stack N` (or --max-stack) */
#define GP_MAX_EVENTS_PER_STATE 255  /**< events of one state (a uint8_t count) */
#define GP_MAX_PROFILE_ALTERNATIVES 8  /**< `flightprofile a | b | ...` alternatives of one state */
#define GP_MAX_PROFILE_ARGS 7  /**< arguments of one flight profile */
#define GP_MAX_ROUTE_POINTS 64  /**< (lat, lon) points of one state's route */
#define GP_MAX_SWEEP_WAYPOINTS 256  /**< waypoints a `sweep` route expands to */
/** characters of a mission, state or computer name in a plan file */
#define GP_MAX_NAME_LENGTH 32
#define GP_MAX_PLAN_SENSORS 16  /**< `sensor` lines of one state block of a plan file */
#define GP_MAX_PLAN_BYTES 65536  /**< size of a plan file [bytes] */
#define GP_MAX_PLAN_LINE_BYTES 255  /**< length of a plan-file line, its LF included [bytes] */
#define GP_MAX_PLAN_COMPONENTS 16  /**< energy components a plan predicts (its `components` line) */
#define GP_MAX_PLAN_ASSUMPTIONS 255  /**< `assume` lines of a plan file (a uint8_t count) */
#define GP_PLAN_FORMAT_VERSION 3  /**< the plan file's `GPPLAN` line (docs/plan-format.md) */

/* ---- what a plan may ask for */

/** [s] a cycle, a sensor period, a state's predicted time (10 y) */
#define GP_MAX_PLAN_TIME_S 315360000.0
#define GP_MAX_PLAN_SPEED_MPS 2.0  /**< [m/s] a planned horizontal speed (a glider makes 0.2-0.5) */
/** [W] a yo's thruster's commanded power (the Slocum G3 hybrid's commands 1-9 W) */
#define GP_MAX_PLAN_THRUST_W 100.0
/** [J] a budget or prediction (the largest Slocum pack is 12 MJ) */
#define GP_MAX_PLAN_ENERGY_J 10000000000.0
/** a state's predicted inflections (as many as its visits may be) */
#define GP_MAX_PLAN_INFLECTIONS 1000000000.0
#define GP_MAX_BOARD_CLOCKS 8  /**< clocks of one board the compiled mission lists */
#define GP_CLOCK_TOLERANCE_MHZ 1e-06  /**< [MHz] a plan's clock is the board's within this */
#define GP_NO_BOARD "none"  /**< `computer none`: no board to set; its plans' clocks are all 0 */
/** A plan's figures are written with 9 significant digits: two that should agree (a duty and its bound, the prediction and its states' sum) agree within this relative tolerance. */
#define GP_PLAN_ROUNDING 1e-06

/* ---- signed plans */

#define GP_PLAN_KEY_BYTES 32  /**< [bytes] of the HMAC-SHA256 key provisioned on the vehicle */
#define GP_MAX_PLAN_SEQUENCE 4294967295  /**< a signed plan's `seq` (a u32); 1 is the first */

/* ---- plan updates (docs/plan-update.md) */

#define GP_UPDATE_FORMAT_VERSION 1  /**< the update's version byte; a reader rejects any other */
#define GP_MAX_UPDATE_BYTES 270  /**< [bytes] of one update, its tag included */
/** [bytes] of SHA-256 that name the plan an update is for, and its result */
#define GP_UPDATE_HASH_BYTES 8
/** [bytes] magic, version, seqs, hashes, the count of changes */
#define GP_UPDATE_HEADER_BYTES 28
#define GP_UPDATE_MAX_DIGITS 15  /**< decimal digits of a value's mantissa: exact in a double */
/** a value is mantissa x 10^exponent, |exponent| at most this */
#define GP_UPDATE_MAX_EXPONENT 20

/* ---- the library routines (docs/pilot.md) */

#define GP_SURFACE_PITCH_RAD 0.454  /**< [rad] pitch of the climb to the surface */
#define GP_TRACK_WINDOW 64  /**< (depth, temp) readings the thermocline tracker keeps per leg */
#define GP_YO_ALTITUDE_ARG 4  /**< yo's argument: a dive turns at this height above the sea floor */
#define GP_THERMOTRACKYO_ALTITUDE_ARG 6  /**< thermotrackyo's argument, as yo's */
#define GP_WAYPOINT_RADIUS_M 50.0  /**< [m] a waypoint closer than this is reached */
/** [m] of the sphere positions and headings are computed on */
#define GP_EARTH_RADIUS_M 6371000.0

/* ---- the serial link (docs/protocol.md) */

/** 2: COMMANDs as changes against a base, SENSORS without a mask; */
#define GP_PROTOCOL_VERSION 3
#define GP_MAX_PAYLOAD 240  /**< [bytes] of one frame's payload */
#define GP_MAX_WIRE 250  /**< [bytes] of COBS before the delimiter that a receiver accepts */
#define GP_PLAN_PIECE 200  /**< [bytes] of plan file per PLAN frame */
#define GP_COMMAND_MAX_SIZE 46  /**< [bytes] of a COMMAND payload that carries every field */
/** [bytes] of HELLO's mission hash (raw SHA-256 of the mission) */
#define GP_MISSION_HASH_BYTES 32
/** [bytes] of HELLO before the mission's name: protocol, n_sensors, read_mask, hash, name_len */
#define GP_HELLO_FIXED_BYTES 39
#define GP_NO_STATE 0xFFu  /**< COMMAND's `state` once exited; `from`/`to` of no state */
#define GP_BAUD 115200  /**< 8N1: 10 bits per byte on the line */
/** [ms] a frame unanswered this long is sent again (science computer's frames, runtime's HELLO) */
#define GP_RETRANSMIT_MS 200
/** [s] the watchdog: the runtime releases the glider after this long without a valid frame */
#define GP_LINK_TIMEOUT_S 10.0

/* ---- the sensor array: GP_SENSOR_<NAME> is the index of sensor NAME */

#define GP_N_SENSORS 24  /**< the array's length (HELLO's `n_sensors`); at most 32 (u32 masks) */
/** Sensors without a device of their own: always powered while logged, in the hotel load. */
#define GP_FLIGHT_SENSORS_MASK 0x3E01FFu

enum {
    GP_SENSOR_MISSIONTIME = 0,  /**< time since the mission started [s] */
    GP_SENSOR_DEPTH = 1,  /**< depth below the surface, positive down [m] */
    GP_SENSOR_PITCH = 2,  /**< vehicle pitch, positive nose up [rad] */
    GP_SENSOR_ROLL = 3,  /**< vehicle roll [rad] */
    GP_SENSOR_HEADING = 4,  /**< magnetic heading [rad] */
    GP_SENSOR_ALTITUDE = 5,  /**< height above the sea floor [m] */
    GP_SENSOR_LAT = 6,  /**< latitude, Slocum degrees and minutes [DDMM.MMMM] */
    GP_SENSOR_LON = 7,  /**< longitude, Slocum degrees and minutes [DDMM.MMMM] */
    GP_SENSOR_BATTERY = 8,  /**< battery voltage [V] */
    GP_SENSOR_TEMP = 9,  /**< water temperature (CTD) [degC] */
    GP_SENSOR_CONDUCTIVITY = 10,  /**< water conductivity (CTD) [S/m] */
    GP_SENSOR_SALINITY = 11,  /**< practical salinity (CTD) [PSU] */
    GP_SENSOR_OXYGEN = 12,  /**< dissolved oxygen (optode) [umol/kg] */
    GP_SENSOR_CHLOROPHYLL = 13,  /**< chlorophyll fluorescence (optics) [ug/l] */
    GP_SENSOR_BACKSCATTER = 14,  /**< optical backscatter (optics) [1/m] */
    GP_SENSOR_CURRENT = 15,  /**< water current speed (ADCP) [m/s] */
    GP_SENSOR_MODEM = 16,  /**< bytes received by the acoustic modem [B] */
    /** the yo's leg flown since the profile was entered (1: the first dive or climb); 0 outside a yo [1] */
    GP_SENSOR_HALFCYCLE = 17,
    /** distance to the waypoint the route flies to; NaN without one or without a position [m] */
    GP_SENSOR_WPTDIST = 18,
    GP_SENSOR_TIMEOFDAY = 19,  /**< UTC time of day of the glider's clock, 0 at midnight [s] */
    /** energy left in the battery: its capacity less what the coulomb counter counted (the energy guard reads it) [J] */
    GP_SENSOR_ENERGY_LEFT = 20,
    /** waypoints the route has reached since the state was entered (a goto list counts on, lap after lap); 0 for nav and noheading [1] */
    GP_SENSOR_WPTREACHED = 21,
    GP_SENSOR_GROUNDSPEED = 22,  /**< speed over the sea floor (DVL bottom track) [m/s] */
    GP_SENSOR_SHEAR = 23,  /**< microstructure velocity shear (microstructure logger) [1/s] */
};

/* ---- COMMAND's flags */

enum {
    GP_FLAG_SURFACE = 1u,  /**< go to (or stay at) the surface */
    GP_FLAG_DONE = 2u,  /**< the mission exited */
    GP_FLAG_CLIMBING = 4u,  /**< else diving */
    GP_FLAG_HEADING = 8u,  /**< `heading_rad` is valid */
    GP_FLAG_ENVELOPE = 16u,  /**< the envelope guard held this command at the vehicle's rating */
    GP_FLAG_HEADING_HOLD = 32u,  /**< `heading_rad` is held as it is, uncorrected for the current */
};

/* ---- SENSORS's flags */

enum {
    /** a u32 mask follows; else the values are those of HELLO's read_mask */
    GP_SENSORS_MASK = 1u,
    GP_SENSORS_RESYNC = 2u,  /**< answer with a whole COMMAND: the last one could not be applied */
};

/** Bytes of each COMMAND field on the wire, in gp_command_field order. */
#define GP_COMMAND_FIELD_BYTES {1, 1, 1, 1, 1, 1, 1, 4, 4, 4, 4, 4, 4, 4, 4}
#define GP_N_COMMAND_FIELDS 15

/** The type byte of a frame's header. */
typedef enum {
    GP_MSG_HELLO = 0x01, GP_MSG_SENSORS = 0x02, GP_MSG_COMMAND = 0x03, GP_MSG_RELEASE = 0x04,
    GP_MSG_PLAN = 0x05, GP_MSG_PLAN_STATUS = 0x06,
    /** pieces of a plan update (docs/plan-update.md), as PLAN carries plans */
    GP_MSG_PLAN_UPDATE = 0x07,
    GP_MSG_UPDATE_STATUS = 0x08,  /**< what became of the update: applied, or why not */
    GP_MSG_NAK = 0x7F,
} gp_msg_type;

/** COMMAND's `transition` field, the event log's `kind` and an event's action. */
typedef enum {
    GP_TR_NONE = 0, GP_TR_START = 1, GP_TR_GOTO = 2, GP_TR_CALL = 3, GP_TR_RETURN = 4,
    GP_TR_EXIT = 5,
    GP_TR_RESERVE = 6,  /**< the energy guard ended the mission: the battery reached its reserve */
    /** the envelope guard ended the mission: a command outside the vehicle's rating */
    GP_TR_ENVELOPE = 7,
} gp_transition_kind;

/** A COMMAND's fields in wire order: bit i of its `fields` says that field i follows. */
typedef enum {
    GP_CMD_STATE = 0,  /**< u8 state index after the tick, NO_STATE once exited */
    GP_CMD_STACK_DEPTH = 1,  /**< u8 stack depth after the tick */
    GP_CMD_TRANSITION = 2,  /**< u8 TransitionKind of the tick (NONE on most) */
    GP_CMD_FROM_STATE = 3,  /**< u8 state the transition left, NO_STATE: none */
    GP_CMD_TO_STATE = 4,  /**< u8 state the transition entered, NO_STATE: none */
    GP_CMD_PROFILE = 5,  /**< u8 index of the flight-profile alternative flown */
    GP_CMD_FLAGS = 6,  /**< u8 FLAG_* bits */
    GP_CMD_DEPTH_TARGET_M = 7,  /**< f32 [m] */
    GP_CMD_PITCH_RAD = 8,  /**< f32 [rad], positive nose up */
    GP_CMD_BALLAST_CC = 9,  /**< f32 [cc] pumped from neutral, positive buoyant */
    GP_CMD_HEADING_RAD = 10,  /**< f32 [rad] true, clockwise from north (valid with FLAG_HEADING) */
    GP_CMD_SENSOR_POWER = 11,  /**< u32 bit i: power sensor i's device */
    GP_CMD_EVENT_COUNT = 12,  /**< u32 events fired so far */
    GP_CMD_SPEED_MPS = 13,  /**< f32 [m/s] through the water on the propeller; 0: none (a glide) */
    /** f32 [W] a glider's thruster's commanded power assisting a yo; 0: off */
    GP_CMD_THRUST_W = 14,
} gp_command_field;

/** RELEASE's `reason`: why the runtime gave control back to the glider. */
typedef enum {
    GP_RELEASE_LINK_SILENT = 1,  /**< no valid frame for the link timeout (the watchdog) */
    /** a mission fault, I/O that failed, a crash or a stop signal */
    GP_RELEASE_INTERNAL_ERROR = 2,
    GP_RELEASE_MISSION_EXITED = 3,
    GP_RELEASE_ENERGY_RESERVE = 4,  /**< the energy guard ended the mission: surface and hold */
    /** a command outside the vehicle's rating: the envelope guard acted */
    GP_RELEASE_ENVELOPE = 5,
} gp_release_reason;

/** Exit status of a mission binary (runtime/README.md). */
typedef enum {
    GP_EXIT_DONE = 0,  /**< the mission exited */
    GP_EXIT_BAD_INPUT = 1,  /**< bad arguments, plan or checkpoint */
    GP_EXIT_LINK_LOST = 3,  /**< the watchdog: the link went silent */
    GP_EXIT_INTERNAL = 4,  /**< a mission fault, I/O that failed, a crash or a stop signal */
    /** the energy guard ended the mission: the battery reached its reserve */
    GP_EXIT_RESERVE = 5,
    /** a command outside the vehicle's rating: the envelope guard ended it */
    GP_EXIT_ENVELOPE = 6,
} gp_exit_status;

/** What a change of a plan update sets (a field of one plan-file line). */
typedef enum {
    GP_UF_STATE_CLOCK = 1,  /**< `state NAME CLOCK_MHZ ...`: field 2 */
    GP_UF_STATE_CYCLE = 2,  /**< `state ... CYCLE_S ...`: field 3 */
    GP_UF_POWER_SLEEP = 3,  /**< `power SLEEP CYCLES_PER_TICK`: field 1 */
    GP_UF_POWER_CYCLES = 4,  /**< field 2 */
    GP_UF_SENSOR_PERIOD = 5,  /**< `sensor NAME PERIOD_S ON_S`: field 2 */
    GP_UF_SENSOR_ON = 6,  /**< field 3 */
    GP_UF_PROFILE_SHARE = 7,  /**< `profile INDEX SHARE PITCH_RAD BALLAST_CC SPEED_MPS`: field 2 */
    GP_UF_PROFILE_PITCH = 8,  /**< field 3 */
    GP_UF_PROFILE_BALLAST = 9,  /**< field 4 */
    GP_UF_PROFILE_SPEED = 10,  /**< field 5 */
    /** `profile ... THRUST_W`: field 6, appended where the line has none */
    GP_UF_PROFILE_THRUST = 11,
} gp_update_field;

/** UPDATE_STATUS's `status`: what became of a plan update (docs/plan-update.md). */
typedef enum {
    GP_UPDATE_APPLIED = 0,  /**< the new plan is in force from the next tick */
    /** the update that made the plan in force, sent again: nothing to do */
    GP_UPDATE_DUPLICATE = 1,
    GP_UPDATE_NO_KEY = 2,  /**< no key is provisioned on the vehicle: no update is trusted */
    /** not an update, another version, or a change that cannot be made */
    GP_UPDATE_MALFORMED = 3,
    GP_UPDATE_FORGED = 4,  /**< the tag does not match: changed after signing, or another key */
    GP_UPDATE_STALE = 5,  /**< not newer than the plan in force: replayed or stale */
    GP_UPDATE_NOT_HELD = 6,  /**< made against a plan the vehicle does not hold */
    /** made against a plan newer than the one in force: one is missing */
    GP_UPDATE_OUT_OF_ORDER = 7,
    GP_UPDATE_BAD_PLAN = 8,  /**< the plan it makes breaks the format or the vehicle's limits */
    GP_UPDATE_NOT_STORED = 9,  /**< the new plan could not be stored: the plan in force stays */
} gp_update_status;

/** What the runtime does with a command outside the vehicle's envelope. */
typedef enum {
    /** release control to the glider's own layered control, as a mission fault */
    GP_ENVELOPE_FAULT = 0,
    /** the mission's abort: it ends there, the glider surfaces and holds */
    GP_ENVELOPE_SURFACE = 1,
    /** hold the command at the envelope's edge, fly on (a band or rate: as SURFACE) */
    GP_ENVELOPE_CLAMP = 2,
} gp_envelope_action;

/** Which limit of the envelope a command broke (the event log's `envelope` record). */
typedef enum {
    GP_LIMIT_NONE = 0,
    GP_LIMIT_DEPTH = 1,  /**< a depth target, or a yo's end, outside 0..max_depth */
    GP_LIMIT_PITCH = 2,  /**< |pitch| above max_pitch */
    GP_LIMIT_BALLAST = 3,  /**< |pumped volume| above the pump's max_ballast */
    GP_LIMIT_BAND = 4,  /**< a yo band thinner than min_yo_band: it would turn all the time */
    GP_LIMIT_INFLECTION = 5,  /**< a yo turned again sooner than its pump can move a full stroke */
    GP_LIMIT_SPEED = 6,  /**< a propelled speed outside the propulsion's range (0: the motor off) */
    GP_LIMIT_THRUST = 7,  /**< a thruster's commanded power outside its range (0: off) */
    /** the pump's energy over the last hour above its rated mean power */
    GP_LIMIT_PUMP_ENERGY = 8,
} gp_envelope_limit;

#endif /* GP_CONTRACT_H */
