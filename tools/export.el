;;; tools/export.el --- write physics.org as HTML, its code highlighted  -*- lexical-binding: t -*-

;; Usage: emacs -Q --batch -l tools/export.el PAGE.org OUT.html
;;
;; Code is coloured by htmlize (Debian's elpa-htmlize) into CSS classes; the
;; style sheet below gives the colours and lets long code lines scroll inside
;; their block instead of being clipped.  Nothing is evaluated.

;;; Code:

(require 'package)
(let ((dir (car (file-expand-wildcards "/usr/share/emacs/site-lisp/elpa/htmlize-*"))))
  (when dir (add-to-list 'load-path dir)))
(package-initialize)
(require 'org)
(require 'ox-html)
(unless (require 'htmlize nil t)
  (message "export.el: htmlize is missing (Debian: apt-get install elpa-htmlize)")
  (kill-emacs 1))

(set-language-environment "UTF-8")
(setq org-confirm-babel-evaluate nil
      org-export-use-babel nil
      org-html-htmlize-output-type 'css
      org-html-validation-link nil
      ;; the mutant records' drawers are for the tools, not the reader
      org-export-with-drawers nil
      org-html-head-include-default-style t
      make-backup-files nil
      coding-system-for-write 'utf-8-unix)

(defconst luv-export-style
  "<style>
  body { font-family: sans-serif; line-height: 1.45; }
  #content { max-width: 62em; }
  /* a long code line scrolls inside its block; it is never cut off */
  pre, pre.src { overflow-x: auto; white-space: pre; max-width: 100%; }
  pre.src { background: #fbfbf8; }
  /* the section an address points at */
  h2:target, h3:target, h4:target { background: #fff1b8; }
  img { max-width: 100%; height: auto; }
  table { font-size: 92%; }
  /* htmlize's classes (org-html-htmlize-output-type css) */
  .org-keyword { color: #7a2a91; font-weight: bold; }
  .org-builtin { color: #4a3aa8; }
  .org-string { color: #a0522d; }
  .org-doc { color: #6b5a2f; }
  .org-function-name { color: #0b57a4; font-weight: bold; }
  .org-variable-name { color: #8b4500; }
  .org-type { color: #1c7a3a; }
  .org-constant { color: #1c6f7a; }
  .org-comment, .org-comment-delimiter { color: #8a8a8a; font-style: italic; }
  .org-warning { color: #b00020; font-weight: bold; }
</style>"
  "The style sheet added to the page's head: colours for htmlize's classes, code that scrolls,
and the section an address points at marked.")

(setq org-html-head-extra luv-export-style)

(let* ((args command-line-args-left)
       (page (nth 0 args)) (out (nth 1 args)))
  (setq command-line-args-left nil)
  (unless (and page out)
    (message "export.el: usage: emacs -Q --batch -l tools/export.el PAGE.org OUT.html")
    (kill-emacs 1))
  (with-current-buffer (find-file-noselect page)
    (org-export-to-file 'html out))
  (message "html: wrote %s" out))
