;;; tools/tangle.el --- check an Org page, then tangle it reproducibly  -*- lexical-binding: t -*-

;; Usage: emacs -Q --batch -l tools/tangle.el PAGE.org...
;;
;; Each page is checked before anything is written.  The first problem is
;; reported as one line, "PAGE:LINE: what is wrong", and Emacs exits with
;; status 1.  The output depends only on the page and on this Emacs and Org
;; (run with -Q, so no init file can load another Org).

;;; Code:

(require 'org)
(require 'ob-tangle)

(set-language-environment "UTF-8")
(setq org-src-preserve-indentation t          ; block text = tangled text
      org-babel-tangle-use-relative-file-links t ; links say file:../physics.org
      org-confirm-babel-evaluate nil
      make-backup-files nil
      coding-system-for-write 'utf-8-unix)

(defun luv-tangle-fail (format-string &rest args)
  "Print one line made from FORMAT-STRING and ARGS, then exit with status 1."
  (message "%s" (apply #'format format-string args))
  (kill-emacs 1))

(defun luv-tangle-end-with-newline (file)
  "Make the tangled FILE end with a newline, as Org 9.5 leaves it without one."
  (when (and (file-exists-p file)
             (with-temp-buffer
               (insert-file-contents-literally file)
               (and (> (buffer-size) 0)
                    (/= (char-before (point-max)) ?\n))))
    (write-region "\n" nil file t 'silent)))

(defun luv-tangle-problem (file)
  "Return the first structural problem of the Org FILE as a line, or nil.
Checked: every #+begin_src has a language and a matching #+end_src before
the next block or heading; no #+end_src stands alone; block names are
unique; an explicit :tangle target is `no' or a relative path that stays
inside the repository."
  (with-temp-buffer
    (insert-file-contents file)
    (goto-char (point-min))
    (let ((case-fold-search t)
          (names (make-hash-table :test 'equal))
          (line 0) (open nil) (problem nil))
      (while (and (not problem) (not (eobp)))
        (setq line (1+ line))
        (let ((text (buffer-substring-no-properties
                     (line-beginning-position) (line-end-position))))
          (cond
           ((string-match "^[ \t]*#\\+begin_src\\([ \t].*\\)?$" text)
            (let ((header (or (match-string 1 text) "")))
              (cond
               (open
                (setq problem (format "%s:%d: unterminated #+begin_src block (the next one starts at line %d)"
                                      file open line)))
               ((not (string-match "\\`[ \t]+[^ \t:]" header))
                (setq problem (format "%s:%d: #+begin_src without a language" file line)))
               ((and (string-match ":tangle[ \t]+\\([^ \t]+\\)" header)
                     (let ((target (match-string 1 header)))
                       (and (not (string= target "no"))
                            (or (file-name-absolute-p target)
                                (string-match-p "\\(\\`\\|/\\)\\.\\.\\(/\\|\\'\\)" target)
                                (string= target "yes")))))
                (setq problem (format "%s:%d: :tangle must be `no' or a relative file name inside the repository"
                                      file line)))
               (t (setq open line)))))
           ((string-match "^[ \t]*#\\+end_src[ \t]*$" text)
            (if open
                (setq open nil)
              (setq problem (format "%s:%d: #+end_src without #+begin_src" file line))))
           ((and open (string-match "^\\*+ " text))
            (setq problem (format "%s:%d: unterminated #+begin_src block (a heading follows at line %d)"
                                  file open line)))
           ((and (not open) (string-match "^[ \t]*#\\+name:[ \t]*\\(.*?\\)[ \t]*$" text))
            (let* ((name (match-string 1 text))
                   (first (gethash name names)))
              (if first
                  (setq problem (format "%s:%d: block name %s is already used at line %d"
                                        file line name first))
                (puthash name line names))))))
        (forward-line 1))
      (or problem
          (and open (format "%s:%d: unterminated #+begin_src block" file open))))))

(let ((files command-line-args-left))
  (setq command-line-args-left nil)
  (unless files
    (luv-tangle-fail "tangle.el: no Org file given"))
  (dolist (file files)
    (unless (file-readable-p file)
      (luv-tangle-fail "%s: no such file" file))
    (let ((problem (luv-tangle-problem file)))
      (when problem
        (luv-tangle-fail "%s" problem)))
    (condition-case err
        (mapc #'luv-tangle-end-with-newline (org-babel-tangle-file file))
      (error (luv-tangle-fail "%s: tangling failed: %s" file (error-message-string err))))))

;;; tangle.el ends here
