/* ccmap_app message dispatch: by message ID, then by function code with a length check. */
#ifndef CCMAP_APP_DISPATCH_H
#define CCMAP_APP_DISPATCH_H

#include "cfe.h"

void CCMAP_APP_TaskPipe(const CFE_SB_Buffer_t *SBBufPtr);
/* True if the message is ExpectedLength bytes; else an event and CommandErrorCounter + 1. */
bool CCMAP_APP_VerifyLength(const CFE_MSG_Message_t *MsgPtr, size_t ExpectedLength);

#endif
