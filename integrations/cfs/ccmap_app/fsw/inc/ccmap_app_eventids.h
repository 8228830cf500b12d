/* ccmap_app event IDs: every refusal and fault has its own. */
#ifndef CCMAP_APP_EVENTIDS_H
#define CCMAP_APP_EVENTIDS_H

#define CCMAP_APP_RESERVED_EID      0
#define CCMAP_APP_INIT_INF_EID      1  /* initialised (version, map preset) */
#define CCMAP_APP_NOOP_INF_EID      2
#define CCMAP_APP_RESET_INF_EID     3
#define CCMAP_APP_CLEAR_INF_EID     4
#define CCMAP_APP_SAVE_INF_EID      5  /* snapshot written: file, bytes */
#define CCMAP_APP_LOAD_INF_EID      6  /* snapshot loaded: file */
#define CCMAP_APP_PUBLISH_INF_EID   7  /* product published: sequence, CRC */
#define CCMAP_APP_TBL_INF_EID       8  /* parameter table applied (kept the map, or re-initialised it) */
#define CCMAP_APP_MID_ERR_EID       20 /* message ID the app does not take */
#define CCMAP_APP_CC_ERR_EID        21 /* unknown function code */
#define CCMAP_APP_LEN_ERR_EID       22 /* command or frame-ready message of the wrong length */
#define CCMAP_APP_PIPE_ERR_EID      23 /* software-bus read failed: the app exits */
#define CCMAP_APP_INIT_ERR_EID      24 /* start-up failed (pipe, subscription, table, map) */
#define CCMAP_APP_TBL_VAL_ERR_EID   25 /* table refused by the library's validation: the old one stays */
#define CCMAP_APP_TBL_ERR_EID       26 /* table services failed, or a validated table the map refused */
#define CCMAP_APP_FRAME_ERR_EID     27 /* frame-ready refused: bad slot or sequence, slot not ready */
#define CCMAP_APP_UPDATE_ERR_EID    28 /* the library refused a frame as a whole */
#define CCMAP_APP_BUDGET_ERR_EID    29 /* a frame's handling exceeded the table's cycle budget */
#define CCMAP_APP_FILE_ERR_EID      30 /* SAVE/LOAD: file open, read or write failed */
#define CCMAP_APP_SNAPSHOT_ERR_EID  31 /* SAVE/LOAD: the library refused the snapshot */
#define CCMAP_APP_CLEAR_ERR_EID     32 /* CLEAR: the map refused re-initialisation */
#define CCMAP_APP_PUBLISH_ERR_EID   33 /* PUBLISH: the library refused, or the read-back failed */
#define CCMAP_APP_HEALTH_ERR_EID    34 /* housekeeping: the map's state check failed (CORRUPT) */
#define CCMAP_APP_LIB_FAULT_EID     35 /* the library's fault hook: a contract violation inside it */

#endif
