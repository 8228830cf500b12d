/* ccmap_app command function codes (on CCMAP_APP_CMD_MID). Every command has a fixed length
 * (ccmap_app_msg.h); a command of another length or an unknown code is refused with an event and
 * counted in CommandErrorCounter. */
#ifndef CCMAP_APP_FCNCODES_H
#define CCMAP_APP_FCNCODES_H

#define CCMAP_APP_NOOP_CC           0 /* no payload: counts, answers with the version */
#define CCMAP_APP_RESET_COUNTERS_CC 1 /* no payload: the app's and the library's counters to 0 */
#define CCMAP_APP_CLEAR_CC          2 /* no payload: the map empty, parameters kept */
#define CCMAP_APP_SAVE_CC           3 /* CCMAP_APP_FileCmd_t: snapshot of the map to a file */
#define CCMAP_APP_LOAD_CC           4 /* CCMAP_APP_FileCmd_t: the map from a snapshot file, all or nothing */
#define CCMAP_APP_PUBLISH_CC        5 /* no payload: the hazard product, its summary as telemetry */
#define CCMAP_APP_LOAD_TABLE_CC     6 /* CCMAP_APP_FileCmd_t: the parameter table from a table file
                                         (CFE_TBL_Load: validated by the library, applied at once,
                                         or refused with the old table kept) */

#endif
