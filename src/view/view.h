/* src/view/view.h — the interactive viewer (thorax view; paper 4.2, 3.2): GTK 4 windows of linked
 * surfaces drawn by the picture module (include/thorax/picture/picture.h). The only code that links
 * GTK. */
#ifndef THORAX_VIEW_H
#define THORAX_VIEW_H
#endif
