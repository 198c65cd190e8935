;;; tests/editor.el --- the editor's checks, run by tools/editor-test  -*- lexical-binding: t -*-

;; Run in `emacs -Q --batch' with Debian's slime on the load path and
;; tools/luv-physics.el loaded.  Environment: LUV_PORT (swank's port on
;; 127.0.0.1), LUV_ROOT (the repository), LUV_COPY (a copy of physics.org beside
;; a luv-physics.asd and the tangled files, which the checks edit).  Each check
;; prints one line; the last line counts them; the exit status is 1 if any failed.

;;; Code:

(require 'cl-lib)
(require 'slime)
(setq slime-contribs nil)
(slime-setup '())

(defvar editor-test-passed 0)
(defvar editor-test-failed 0)
(defvar editor-test-connected nil)

(defun editor-test-check (name ok &rest detail)
  "Count and print the check NAME, passed when OK; DETAIL is printed when it fails."
  (if ok
      (progn (cl-incf editor-test-passed) (message "editor-test: ok: %s" name))
    (cl-incf editor-test-failed)
    (message "editor-test: FAILED: %s%s" name (if detail (format " %S" detail) ""))))

(defun editor-test-line ()
  "The text of the current line."
  (buffer-substring-no-properties (line-beginning-position) (line-end-position)))

(defun editor-test-lisp (text)
  "Evaluate the Common Lisp TEXT in the image, in CL-USER; return its value."
  (slime-eval `(cl:eval (cl:read-from-string ,text)) "COMMON-LISP-USER"))

(defun editor-test-choose (prefix)
  "A `completing-read' that takes the first candidate starting with PREFIX."
  (lambda (_prompt collection &rest _)
    (car (cl-find-if (lambda (c) (string-prefix-p prefix (car c))) collection))))

(defun editor-test-finish ()
  "Print the count and end Emacs."
  (message "editor-test: %d passed, %d failed" editor-test-passed editor-test-failed)
  (kill-emacs (if (and (zerop editor-test-failed) (> editor-test-passed 0)) 0 1)))

(condition-case err
    (let ((copy (getenv "LUV_COPY"))
          (page (expand-file-name "physics.org" (getenv "LUV_ROOT")))
          (deadline (+ (float-time) 60)))
      (add-hook 'slime-connected-hook (lambda () (setq editor-test-connected t)) t)
      (slime-connect "127.0.0.1" (string-to-number (getenv "LUV_PORT")))
      (while (and (not editor-test-connected) (< (float-time) deadline))
        (accept-process-output nil 0.05))
      (editor-test-check "SLIME connected to the image on 127.0.0.1" (slime-connected-p))

      ;; Anchor -> definition, from inside a section, with completion.
      (find-file copy)
      (editor-test-check "luv-physics-mode is on in the page" luv-physics-mode)
      (goto-char (point-min))
      (re-search-forward "^:CUSTOM_ID: BSOZ3U$")
      (forward-line 3)
      (cl-letf (((symbol-function 'completing-read) (editor-test-choose "anchor-definitions ")))
        (call-interactively #'luv-physics-definitions))
      (editor-test-check "anchor -> definition lands on the definition's line of the page"
                         (and (equal buffer-file-name copy)
                              (string-prefix-p "(defun anchor-definitions (anchor)" (editor-test-line)))
                         (editor-test-line))
      ;; ... from a link, and with a prefix argument to the tangled file
      (goto-char (point-min))
      (search-forward "[[#BSOZ3U][")
      (cl-letf (((symbol-function 'completing-read) (editor-test-choose "definition-anchor ")))
        (let ((current-prefix-arg '(4)))
          (call-interactively #'luv-physics-definitions)))
      (editor-test-check "link -> definition, C-u: the definition's line in the tangled file"
                         (and (string-suffix-p "tangled/workshop.lisp" buffer-file-name)
                              (string-prefix-p "(defun definition-anchor (name" (editor-test-line)))
                         buffer-file-name (editor-test-line))

      ;; What the image knows of a section.
      (switch-to-buffer (find-buffer-visiting copy))
      (goto-char (point-min))
      (re-search-forward "^:CUSTOM_ID: BSOZ3U$")
      (luv-physics-section)
      (editor-test-check "C-c M-s shows the section's definitions and claims"
                         (with-current-buffer "*luv-physics section*"
                           (and (string-match-p "definition-anchor-finds-its-section" (buffer-string))
                                (string-match-p "register-tangled-file" (buffer-string)))))
      ;; its message says "Type q": the q must reach the section's window, not the page
      (let ((page-tick (buffer-chars-modified-tick (find-buffer-visiting copy)))
            (selected (buffer-name (window-buffer (selected-window)))))
        (execute-kbd-macro (kbd "q"))
        (editor-test-check "C-c M-s selects its window, and q closes it without touching the page"
                           (and (equal selected "*luv-physics section*")
                                (null (get-buffer-window "*luv-physics section*"))
                                (= page-tick (buffer-chars-modified-tick (find-buffer-visiting copy)))
                                (eq (window-buffer (selected-window)) (find-buffer-visiting copy)))
                           selected (buffer-name (window-buffer (selected-window)))))

      ;; Symbol -> page, from a Lisp buffer in CL-USER.
      (switch-to-buffer (get-buffer-create "*editor-test lisp*"))
      (lisp-mode)
      (slime-mode 1)
      (insert "(physics:step-physics-world world)")
      (goto-char 12)
      (call-interactively #'luv-physics-page-definition)
      (editor-test-check "symbol -> page lands on the definition's line"
                         (and (equal buffer-file-name page)
                              (string-prefix-p "(defun step-physics-world (world" (editor-test-line)))
                         buffer-file-name (editor-test-line))

      ;; C-c ' on a block: the edit buffer is in the engine's package, so M-. finds
      ;; internal symbols there.
      (switch-to-buffer (find-buffer-visiting copy))
      (goto-char (point-min))
      (re-search-forward "^(defun anchor-definitions")
      (org-edit-special)
      (editor-test-check "the C-c ' edit buffer's package is the engine's"
                         (equal "LUV-PHYSICS" (slime-current-package)) (slime-current-package))
      (let ((found (slime-eval '(swank:find-definitions-for-emacs "solver-row"))))
        (editor-test-check "M-. in the edit buffer finds the internal solver-row"
                           (and found (not (eq :error (car (cadr (car found))))))
                           found))
      (org-edit-src-abort)
      (editor-test-check "... where a CL-USER buffer finds no solver-row"
                         (null (slime-eval '(swank:find-definitions-for-emacs "solver-row") "COMMON-LISP-USER")))

      ;; Reload an edited phase into stepping worlds of every family this CPU runs.
      (editor-test-lisp "(progn
         (defvar *phase-calls* 0)
         (defun count-phase (world) (incf *phase-calls*) world)
         (setf physics:*physics-phases* (append physics:*physics-phases* '(count-phase)))
         (defparameter *worlds*
           (mapcar (lambda (family)
                     (let* ((w (physics:make-physics-world :kernels family))
                            (h (physics:add-physics-body w 0.5 10 0.5)))
                       (dotimes (i 10) (physics:step-physics-world w))
                       (cons w h)))
                   (physics:available-kernel-families)))
         (defun vys () (mapcar (lambda (wh) (nth-value 1 (physics:physics-body-velocity (car wh) (cdr wh)))) *worlds*))
         (defun step-all () (dolist (wh *worlds*) (physics:step-physics-world (car wh))))
         t)")
      (switch-to-buffer (find-buffer-visiting copy))
      (goto-char (point-min))
      ;; the phase's own call, not a claim's that makes the same call
      (re-search-forward "^(defun substep-phase (world)")
      (re-search-forward "(physics-integrate-velocities kernels world h)")
      (replace-match "(physics-integrate-velocities kernels world (- h))" t t)
      (let* ((before (editor-test-lisp "(progn (step-all) (vys))"))
             (calls (editor-test-lisp "*phase-calls*"))
             (started (float-time))
             (handled (org-ctrl-c-ctrl-c))
             (seconds (- (float-time) started))
             (after (editor-test-lisp "(progn (step-all) (vys))"))
             (families (editor-test-lisp "(format nil \"~{~(~A~)~^ ~}\" (physics:available-kernel-families))")))
        (message "editor-test: C-c C-c reloaded the block in %.2f s (families: %s)" seconds families)
        (ignore handled)
        (editor-test-check
         (format "the reloaded phase acts on the next step in every family (%s)" families)
         ;; falling before, a step with gravity reversed raises each ball's vy
         (and before after (= (length before) (length after))
              (cl-every (lambda (b a) (and (< b 0) (> a b))) before after))
         before after)
        (editor-test-check "the changed *physics-phases* kept its value and still runs"
                           (and (editor-test-lisp "(and (member 'count-phase physics:*physics-phases*) t)")
                                (= (editor-test-lisp "*phase-calls*") (+ calls (length before)))))
        ;; M-. on the reloaded function lands on the page
        (let* ((found (slime-eval '(swank:find-definitions-for-emacs "luv-physics::substep-phase")))
               (location (cadr (car found))))
          (slime-goto-source-location location)
          (editor-test-check "M-. on a reloaded function lands on its line of the page"
                             (and (equal buffer-file-name copy)
                                  (string-prefix-p "(defun substep-phase (world)" (editor-test-line)))
                             location (editor-test-line))))

      ;; The inspector, set up when SLIME connected.
      (editor-test-check "the SLIME inspector shows a body's position and mass"
                         (editor-test-lisp "(let ((parts (swank::emacs-inspect
                                                           (physics:physics-body (car (first *worlds*)) (cdr (first *worlds*))))))
                                              (and (find \"position\" parts :test (lambda (a b) (and (stringp b) (search a b))))
                                                   (find \"mass\" parts :test (lambda (a b) (and (stringp b) (search a b))))
                                                   t))"))

      ;; The whole section, timed.
      (switch-to-buffer (find-buffer-visiting copy))
      (goto-char (point-min))
      (re-search-forward "^:CUSTOM_ID: IDVK7G$")
      (let* ((started (float-time))
             (summary (luv-physics-reload-section nil))
             (seconds (- (float-time) started)))
        (message "editor-test: C-c M-r reloaded section IDVK7G in %.2f s: %s" seconds summary)
        (editor-test-check "the section's reload summary is one line with no warnings"
                           (and (stringp summary) (not (string-match-p "\n" summary))
                                (string-match-p " 0 warnings" summary))
                           summary))

      ;; C-c M-u tangles the page anew: a buffer visiting a tangled file takes the new text
      ;; without asking whether to edit a file changed on disk.  (Last: the image then reads
      ;; the copy's tangled files.)
      (let* ((tangled (find-file-noselect (expand-file-name "tangled/physics.lisp" (file-name-directory copy))))
             (old "How many bodies of WORLD are awake.")
             (new "How many bodies of WORLD are awake now."))
        (switch-to-buffer (find-buffer-visiting copy))
        (goto-char (point-min))
        (search-forward old)
        (replace-match new t t)
        (let* ((started (float-time))
               (summary (luv-physics-reload-changed))
               (seconds (- (float-time) started)))
          (message "editor-test: C-c M-u tangled and reloaded in %.2f s: %s" seconds summary)
          (editor-test-check "C-c M-u reloads the edited form"
                             (and (string-match-p "reload changed: 1 form " summary)
                                  (string-prefix-p "How many bodies of WORLD are awake now."
                                                   (editor-test-lisp "(documentation 'physics:physics-world-awake-count 'function)")))
                             summary))
        (with-current-buffer tangled
          (editor-test-check "after C-c M-u a buffer on the tangled file holds the new text, unmodified, with no question"
                             (and (verify-visited-file-modtime tangled)
                                  (not (buffer-modified-p))
                                  (save-excursion (goto-char (point-min)) (search-forward new nil t)))
                             (verify-visited-file-modtime tangled) (buffer-modified-p))))
      (editor-test-finish))
  (error (editor-test-check "the editor checks ran to the end" nil (error-message-string err))
         (editor-test-finish)))

;;; editor.el ends here
