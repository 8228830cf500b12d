/* ccmap_app command handlers: each counts (CommandCounter or CommandErrorCounter) and answers with
 * an event. */
#ifndef CCMAP_APP_CMDS_H
#define CCMAP_APP_CMDS_H

#include "ccmap_app.h"

void CCMAP_APP_NoopCmd(const CCMAP_APP_NoopCmd_t *Msg);
void CCMAP_APP_ResetCountersCmd(const CCMAP_APP_ResetCountersCmd_t *Msg);
void CCMAP_APP_ClearCmd(const CCMAP_APP_ClearCmd_t *Msg);
void CCMAP_APP_SaveCmd(const CCMAP_APP_FileCmd_t *Msg);
void CCMAP_APP_LoadCmd(const CCMAP_APP_FileCmd_t *Msg);
void CCMAP_APP_LoadTableCmd(const CCMAP_APP_FileCmd_t *Msg);
void CCMAP_APP_PublishCmd(const CCMAP_APP_PublishCmd_t *Msg);
void CCMAP_APP_SendHkCmd(const CCMAP_APP_SendHkCmd_t *Msg);

#endif
